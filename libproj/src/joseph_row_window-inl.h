// Per SIMD target: the forward projection's row window. When a bundle's lanes lie within 2N
// neighbouring voxels of a contiguous axis and two neighbouring rows, a sample loads those rows
// whole and picks its corners by permutes; no gathers.
#if defined(CTK_PROJ_JOSEPH_ROW_WINDOW_INL_H_) == defined(HWY_TARGET_TOGGLE)
#ifdef CTK_PROJ_JOSEPH_ROW_WINDOW_INL_H_
#undef CTK_PROJ_JOSEPH_ROW_WINDOW_INL_H_
#else
#define CTK_PROJ_JOSEPH_ROW_WINDOW_INL_H_
#endif

#include <hwy/highway.h>

#include <algorithm>
#include <cstdint>

#include "joseph_samples-inl.h"
#include "ray_table.hpp"
#include "window_lookup-inl.h"

HWY_BEFORE_NAMESPACE();
namespace ctk::detail {
namespace HWY_NAMESPACE {
namespace hn = hwy::HWY_NAMESPACE;

// Where a window bundle's lanes sit in slice k: the first voxel x0 of the 2N-voxel window along
// b (kept inside the row) and the lowest row c0. Lanes step along b (LanePath), so the ends
// decide x0; along c a staircase of lanes spreads over a row or two, so all lanes decide c0.
// The kernels then check every lane against the window.
template <class DF>
HWY_INLINE void window_origin(DF df, const SamplePosition<DF>& p, int n_b, int& x0, int& c0) {
  const auto last = hn::Lanes(df) - 1;
  const int N = static_cast<int>(hn::Lanes(df));
  x0 = std::min(std::max(std::min(hn::GetLane(p.ib), hn::ExtractLane(p.ib, last)), 0), n_b - 2 * N);
  c0 = hn::GetLane(hn::MinOfLanes(hn::RebindToSigned<DF>(), p.ic));
}

// The sample from rows c0 .. c0 + 3 of a window (`row` at row c0, voxel x0; rows sc apart):
// lane l's corners sit at pos[l] and pos[l] + 1 of row dc[l] and the row above.
template <class DF>
HWY_INLINE hn::Vec<DF> window_sample(DF df, const float* HWY_RESTRICT row, std::ptrdiff_t sc, hn::Vec<hn::RebindToSigned<DF>> pos,
                                     hn::Vec<hn::RebindToSigned<DF>> dc, const hn::Vec<DF> (&weight)[4]) {
  const hn::RebindToSigned<DF> di;
  const int N = static_cast<int>(hn::Lanes(df));
  const auto pos1 = hn::Add(pos, hn::Set(di, 1));
  const auto upper = hn::Gt(dc, hn::Zero(di));  // lanes whose corner c sits a row up or two
  const auto top = hn::Eq(dc, hn::Set(di, 2));  // two rows up
  const auto r0lo = hn::LoadU(df, row), r0hi = hn::LoadU(df, row + N);
  const auto r1lo = hn::LoadU(df, row + sc), r1hi = hn::LoadU(df, row + sc + N);
  auto c00 = lookup_window(df, r0lo, r0hi, pos), c10 = lookup_window(df, r0lo, r0hi, pos1);
  auto c01 = lookup_window(df, r1lo, r1hi, pos), c11 = lookup_window(df, r1lo, r1hi, pos1);
  if (!hn::AllFalse(di, upper)) {  // some lanes a row up: shift them by a row
    const auto up = hn::RebindMask(df, upper);
    const auto r2lo = hn::LoadU(df, row + 2 * sc), r2hi = hn::LoadU(df, row + 2 * sc + N);
    const auto c02 = lookup_window(df, r2lo, r2hi, pos), c12 = lookup_window(df, r2lo, r2hi, pos1);
    c00 = hn::IfThenElse(up, c01, c00);
    c10 = hn::IfThenElse(up, c11, c10);
    c01 = hn::IfThenElse(up, c02, c01);
    c11 = hn::IfThenElse(up, c12, c11);
    if (!hn::AllFalse(di, top)) {  // and some two rows up: shift those by one more
      const auto up2 = hn::RebindMask(df, top);
      const auto r3lo = hn::LoadU(df, row + 3 * sc), r3hi = hn::LoadU(df, row + 3 * sc + N);
      c00 = hn::IfThenElse(up2, c02, c00);
      c10 = hn::IfThenElse(up2, c12, c10);
      c01 = hn::IfThenElse(up2, lookup_window(df, r3lo, r3hi, pos), c01);
      c11 = hn::IfThenElse(up2, lookup_window(df, r3lo, r3hi, pos1), c11);
    }
  }
  return weigh(c00, c10, c01, c11, weight);
}

// Whether lanes at `pos` (with their b + 1 corner) and rows `dc` fit the window: 2N voxels, at
// most three neighbouring rows.
template <class DI>
HWY_INLINE bool fits_window(DI di, hn::Vec<DI> pos, hn::Vec<DI> dc) {
  const auto limit = hn::Set(di, static_cast<std::int32_t>(2 * hn::Lanes(di)));
  return hn::AllTrue(di, hn::And(hn::Gt(pos, hn::Set(di, -1)), hn::Lt(hn::Add(pos, hn::Set(di, 1)), limit))) &&
         hn::AllTrue(di, hn::Lt(dc, hn::Set(di, 3)));
}

// The sample of a window bundle (Bundle::window) at a slice outside its interior range, without
// gathers: lanes out of their ray's range take no part (their sample is zero), and every other
// lane must be interior there, its lanes within a window of 2N voxels along b and at most three
// neighbouring values of c. The slice's rows there are loaded whole and each lane picks its
// corners by permutes. False (and `sample` untouched) otherwise; the caller then gathers with
// masks.
template <class DF>
HWY_INLINE bool interpolate_window(DF df, const RayTable& t, const float* HWY_RESTRICT volume, std::size_t r, int k,
                                   hn::Vec<DF>& sample) {
#if HWY_TARGET == HWY_SCALAR
  (void)df, (void)t, (void)volume, (void)r, (void)k, (void)sample;
  return false;
#else
  const hn::RebindToSigned<DF> di;
  const int N = static_cast<int>(hn::Lanes(df));
  const SamplePosition<DF> p = position_at(df, t, r, k);
  hn::Mask<decltype(di)> inside;
  if (!interior_lanes(di, t, r, k, inside)) return false;
  if (hn::AllFalse(di, inside)) {
    sample = hn::Zero(df);
    return true;
  }
  const auto far = hn::Set(di, 1 << 29);
  const int x0 = std::min(std::max(hn::GetLane(hn::MinOfLanes(di, hn::IfThenElse(inside, p.ib, far))), 0), t.n_b[r] - 2 * N);
  const int c0 = hn::GetLane(hn::MinOfLanes(di, hn::IfThenElse(inside, p.ic, far)));
  // The others read the window's first voxel.
  const auto pos = hn::Sub(hn::IfThenElse(inside, p.ib, hn::Set(di, x0)), hn::Set(di, x0));
  const auto dc = hn::Sub(hn::IfThenElse(inside, p.ic, hn::Set(di, c0)), hn::Set(di, c0));
  if (!fits_window(di, pos, dc)) return false;
  const std::ptrdiff_t sc = t.stride_c[r];
  const float* row =
      volume + static_cast<std::ptrdiff_t>(k - t.origin_a) * t.stride_a[r] + static_cast<std::ptrdiff_t>(c0) * sc + x0;
  hn::Vec<DF> weight[4];
  bilinear_weights(p, weight);
  sample = hn::IfThenElseZero(hn::RebindMask(df, inside), window_sample(df, row, sc, pos, dc, weight));
  return true;
#endif
}

// The masked slices [k_lo, k_hi] of a pairs bundle (Bundle::pairs; slices on the volume's rim,
// where lanes enter or leave it at different slices), their samples added to `sum` in order:
// the row window where it applies (Bundle::window), else pair_corners_at's two pairs. Two
// passes, as add_window_samples: first every slice's pairs, their lines asked for with
// Rows::fetch_ahead, then the loads. One slice at a time, each sample's gathers waited for
// their lines: 19 % of ForwardRays' time in spherical views on the Zen 4 (benchmarks/paired.py).
template <class DF>
HWY_INLINE hn::Vec<DF> add_rim_samples(DF df, const RayTable& t, const float* HWY_RESTRICT volume, const Bundle& b, int k_lo,
                                       int k_hi, hn::Vec<DF> sum, Rows fetch) {
  const hn::RebindToSigned<DF> di;
  const int N = static_cast<int>(hn::Lanes(df));
  const auto all = hn::FirstN(df, hn::Lanes(df));
  Corners<DF> corners[kRimBatch];
  HWY_ALIGN std::int32_t row0[kMaxLanes], row1[kMaxLanes];
  for (int k0 = k_lo; k0 <= k_hi; k0 += kRimBatch) {
    const int count = std::min(kRimBatch, k_hi - k0 + 1);
    for (int i = 0; i < count; ++i) {
      corners[i] = pair_corners_at(df, t, b.r, k0 + i, all).corners;
      if (fetch != Rows::fetch_ahead) continue;
      hn::Store(corners[i].index[0], di, row0);
      hn::Store(corners[i].index[2], di, row1);
      prefetch_pair_rows(volume, row0, row1, N);
    }
    for (int i = 0; i < count; ++i) {
      hn::Vec<DF> sample;
      if (!b.window || !interpolate_window(df, t, volume, b.r, k0 + i, sample))
        sample = interpolate_pairs(df, volume, corners[i]);
      sum = hn::Add(sum, sample);
    }
  }
  return sum;
}

// Slices per pass of add_window_samples (below).
inline constexpr int kWindowBatch = 16;

// prefetch_span for a window's rows from `row` (rows sc apart): two, or three when a lane sits
// a row up.
template <int kWidth>
HWY_INLINE void prefetch_window(const float* row, std::ptrdiff_t sc, bool row_up) {
  prefetch_span<kWidth>(row);
  prefetch_span<kWidth>(row + sc);
  if (row_up) prefetch_span<kWidth>(row + 2 * sc);
}

#if HWY_TARGET == HWY_AVX2
// add_window_samples for 8 lanes of AVX2, written with the instructions it needs: the same
// arithmetic (results bit for bit), without what the portable form adds per sample (the
// position's overflow fix-up, see BundlePositionAvx2; clamps and compares done twice, masks
// rebuilt). A lookup in the 16-voxel window is two permutes (vpermps reads the low three bits
// of each index) and a blend on bit 3 moved to the sign.
HWY_INLINE __m256 add_window_samples_avx2(const RayTable& t, const float* HWY_RESTRICT volume, std::size_t r, int k_lo, int k_hi,
                                          __m256 sum, Rows fetch) {
  constexpr int N = 8;
  const std::ptrdiff_t sc = t.stride_c[r];
  const std::ptrdiff_t slice = t.stride_a[r];
  const int x_max = t.n_b[r] - 2 * N, origin_a = t.origin_a;  // read once: the stores below may alias t
  const BundlePositionAvx2 position(t, r);
  const __m256i one = _mm256_set1_epi32(1), two = _mm256_set1_epi32(2), last_pos = _mm256_set1_epi32(2 * N - 2);
  const __m256 one_f = _mm256_set1_ps(1.0f);
  const __m256i x_max_v = _mm256_set1_epi32(x_max), last_lane = _mm256_set1_epi32(N - 1);
  HWY_ALIGN std::int32_t pos[kWindowBatch][N], dc[kWindowBatch][N];
  HWY_ALIGN float fb[kWindowBatch][N], fc[kWindowBatch][N];
  std::ptrdiff_t offset[kWindowBatch];
  int misfit[kWindowBatch];  // nonzero: the slice does not fit the window
  for (int k0 = k_lo; k0 <= k_hi; k0 += kWindowBatch) {
    const int count = std::min(kWindowBatch, k_hi - k0 + 1);
    __m256 kf = _mm256_set1_ps(static_cast<float>(k0));
    std::ptrdiff_t slice_offset = static_cast<std::ptrdiff_t>(k0 - origin_a) * slice;
    for (int i = 0; i < count; ++i, kf = _mm256_add_ps(kf, one_f), slice_offset += slice) {
      __m256i ib, ic;
      __m256 fbi, fci;
      position.at(kf, ib, ic, fbi, fci);
      // x0 and c0 as window_origin finds them, kept in vectors (no lane extractions and scalar
      // clamps on the way to the rows: 4-8 % of a view's forward instructions, benchmarks/paired.py).
      const __m256i x0 = _mm256_min_epi32(_mm256_max_epi32(_mm256_min_epi32(_mm256_broadcastd_epi32(_mm256_castsi256_si128(ib)),
                                                                            _mm256_permutevar8x32_epi32(ib, last_lane)),
                                                           _mm256_setzero_si256()),
                                          x_max_v);
      __m256i c0 = _mm256_min_epi32(ic, _mm256_permute2x128_si256(ic, ic, 1));
      c0 = _mm256_min_epi32(c0, _mm256_shuffle_epi32(c0, _MM_SHUFFLE(1, 0, 3, 2)));
      c0 = _mm256_min_epi32(c0, _mm256_shuffle_epi32(c0, _MM_SHUFFLE(2, 3, 0, 1)));
      const __m256i p = _mm256_sub_epi32(ib, x0), d = _mm256_sub_epi32(ic, c0);
      // Outside the window: p < 0, p + 1 > 2N - 1 or d > 2 (d >= 0), each a sign bit.
      const __m256i out = _mm256_or_si256(_mm256_or_si256(p, _mm256_sub_epi32(last_pos, p)), _mm256_sub_epi32(two, d));
      misfit[i] = _mm256_movemask_ps(_mm256_castsi256_ps(out));
      _mm256_store_si256(reinterpret_cast<__m256i*>(pos[i]), p);
      _mm256_store_si256(reinterpret_cast<__m256i*>(dc[i]), d);
      _mm256_store_ps(fb[i], fbi);
      _mm256_store_ps(fc[i], fci);
      offset[i] = slice_offset + static_cast<std::ptrdiff_t>(_mm256_cvtsi256_si32(c0)) * sc + _mm256_cvtsi256_si32(x0);
      if (fetch == Rows::fetch_ahead) prefetch_window<2 * N>(volume + offset[i], sc, !_mm256_testz_si256(d, d));
    }
    for (int i = 0; i < count; ++i) {
      if (misfit[i] != 0) {
        const hn::Full256<float> df;
        sum = _mm256_add_ps(sum, interpolate_pairs(df, volume, interior_corners_at(df, t, r, k0 + i)).raw);
        continue;
      }
      const __m256 fbv = _mm256_load_ps(fb[i]), fcv = _mm256_load_ps(fc[i]);
      const __m256 gb = _mm256_sub_ps(one_f, fbv), gc = _mm256_sub_ps(one_f, fcv);
      const __m256i p = _mm256_load_si256(reinterpret_cast<const __m256i*>(pos[i])), p1 = _mm256_add_epi32(p, one);
      const __m256 hi0 = _mm256_castsi256_ps(_mm256_slli_epi32(p, 28)), hi1 = _mm256_castsi256_ps(_mm256_slli_epi32(p1, 28));
      const auto lookup = [&](const float* row, __m256i at, __m256 hi) {
        return _mm256_blendv_ps(_mm256_permutevar8x32_ps(_mm256_loadu_ps(row), at),
                                _mm256_permutevar8x32_ps(_mm256_loadu_ps(row + N), at), hi);
      };
      const float* row = volume + offset[i];
      __m256 c00 = lookup(row, p, hi0), c10 = lookup(row, p1, hi1);
      __m256 c01 = lookup(row + sc, p, hi0), c11 = lookup(row + sc, p1, hi1);
      const __m256i d = _mm256_load_si256(reinterpret_cast<const __m256i*>(dc[i]));
      if (!_mm256_testz_si256(d, d)) {  // some lanes a row up: shift them by a row
        const __m256 up = _mm256_castsi256_ps(_mm256_cmpgt_epi32(d, _mm256_setzero_si256()));
        const __m256 c02 = lookup(row + 2 * sc, p, hi0), c12 = lookup(row + 2 * sc, p1, hi1);
        c00 = _mm256_blendv_ps(c00, c01, up);
        c10 = _mm256_blendv_ps(c10, c11, up);
        c01 = _mm256_blendv_ps(c01, c02, up);
        c11 = _mm256_blendv_ps(c11, c12, up);
        const __m256 top = _mm256_castsi256_ps(_mm256_cmpeq_epi32(d, two));
        if (_mm256_movemask_ps(top) != 0) {  // and some two rows up: shift those by one more
          c00 = _mm256_blendv_ps(c00, c02, top);
          c10 = _mm256_blendv_ps(c10, c12, top);
          c01 = _mm256_blendv_ps(c01, lookup(row + 3 * sc, p, hi0), top);
          c11 = _mm256_blendv_ps(c11, lookup(row + 3 * sc, p1, hi1), top);
        }
      }
      // weigh() with bilinear_weights(), unrolled.
      const __m256 sample = _mm256_fmadd_ps(
          c11, _mm256_mul_ps(fbv, fcv),
          _mm256_fmadd_ps(c01, _mm256_mul_ps(gb, fcv),
                          _mm256_fmadd_ps(c10, _mm256_mul_ps(fbv, gc), _mm256_mul_ps(c00, _mm256_mul_ps(gb, gc)))));
      sum = _mm256_add_ps(sum, sample);
    }
  }
  return sum;
}
#endif

// The interior slices [k_lo, k_hi] of a window bundle, their samples added to `sum` in order: the
// rows of the window where the lanes fit it, gathers where they spread wider. Two passes over up
// to kWindowBatch slices: first every slice's window (origin, lanes' places, fractions), then
// the loads. A sample's chain from the table to its rows is long; in one pass the processor had
// fewer than two samples in flight, each waiting for its rows almost alone (10-15 % faster on
// the Zen 3, benchmarks/README.md, benchmarks/paired.py). With Rows::fetch_ahead, the first pass also asks
// for the rows (prefetch_span).
template <class DF>
HWY_INLINE hn::Vec<DF> add_window_samples(DF df, const RayTable& t, const float* HWY_RESTRICT volume, std::size_t r, int k_lo,
                                          int k_hi, hn::Vec<DF> sum, Rows fetch) {
#if HWY_TARGET == HWY_AVX2
  return hn::Vec<DF>{add_window_samples_avx2(t, volume, r, k_lo, k_hi, sum.raw, fetch)};
#else
  const hn::RebindToSigned<DF> di;
  const std::ptrdiff_t sc = t.stride_c[r];
  const std::ptrdiff_t slice = t.stride_a[r];
  const int n_b = t.n_b[r], origin_a = t.origin_a;  // read once, like the rays: the stores below may alias t
  const BundlePosition<DF> position(df, t, r);
  HWY_ALIGN std::int32_t pos[kWindowBatch][kMaxLanes], dc[kWindowBatch][kMaxLanes];
  HWY_ALIGN float fb[kWindowBatch][kMaxLanes], fc[kWindowBatch][kMaxLanes];
  const float* row[kWindowBatch];
  bool fits[kWindowBatch];
  for (int k0 = k_lo; k0 <= k_hi; k0 += kWindowBatch) {
    const int count = std::min(kWindowBatch, k_hi - k0 + 1);
    for (int i = 0; i < count; ++i) {
      const SamplePosition<DF> p = position.at(df, k0 + i);
      int x0, c0;
      window_origin(df, p, n_b, x0, c0);
      const auto pi = hn::Sub(p.ib, hn::Set(di, x0)), dci = hn::Sub(p.ic, hn::Set(di, c0));
      fits[i] = fits_window(di, pi, dci);
      hn::Store(pi, di, pos[i]);
      hn::Store(dci, di, dc[i]);
      hn::Store(p.fb, df, fb[i]);
      hn::Store(p.fc, df, fc[i]);
      row[i] = volume + static_cast<std::ptrdiff_t>(k0 + i - origin_a) * slice + static_cast<std::ptrdiff_t>(c0) * sc + x0;
      if (fetch == Rows::fetch_ahead)
        prefetch_window<2 * static_cast<int>(HWY_LANES(float))>(row[i], sc, !hn::AllFalse(di, hn::Gt(dci, hn::Zero(di))));
    }
    for (int i = 0; i < count; ++i) {
      hn::Vec<DF> sample;
      if (fits[i]) {
        hn::Vec<DF> weight[4];
        bilinear_weights(hn::Load(df, fb[i]), hn::Load(df, fc[i]), weight);
        sample = window_sample(df, row[i], sc, hn::Load(di, pos[i]), hn::Load(di, dc[i]), weight);
      } else {
        sample = interpolate_pairs(df, volume, interior_corners_at(df, t, r, k0 + i));
      }
      sum = hn::Add(sum, sample);
    }
  }
  return sum;
#endif
}

}  // namespace HWY_NAMESPACE
}  // namespace ctk::detail
HWY_AFTER_NAMESPACE();

#endif

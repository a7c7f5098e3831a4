// SIMD kernels of the fast Joseph projector, compiled once per x86 target by Highway and chosen
// at run time. Lanes are neighbouring rays; each lane carries its own axis, strides and range.
#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "joseph_kernels.cpp"
#include <hwy/foreach_target.h>  // IWYU pragma: keep
#include <hwy/highway.h>

#include <algorithm>
#include <vector>

#include "ray_table.hpp"

HWY_BEFORE_NAMESPACE();
namespace ctk::detail {
namespace HWY_NAMESPACE {
namespace hn = hwy::HWY_NAMESPACE;

// The four bilinear corners of the Joseph sample at slice k of N neighbouring rays: voxel
// indices (clamped inside the volume) and weights (zero for corners outside it or lanes outside
// their ray's range). Shared by both directions, so the two are adjoint sample by sample.
template <class DF>
struct Corners {
  using DI = hn::RebindToSigned<DF>;
  hn::Vec<DI> index[4];
  hn::Vec<DF> weight[4];
};

// Where the Joseph sample at slice k falls between voxels: lower corner (ib, ic) and the
// bilinear fractions. Both corner computations below start here, so their weights agree bit
// for bit (which keeps forward and back adjoint whichever path a sample takes).
template <class DF>
struct SamplePosition {
  hn::Vec<hn::RebindToSigned<DF>> ib, ic;
  hn::Vec<DF> fb, fc, gb, gc;  // g = 1 - f
};

// Lane l at slice k[l]; indices relative to the grid's origin (RayTable::origin_b, origin_c).
template <class DF>
HWY_INLINE SamplePosition<DF> position_at(DF df, const RayTable& t, std::size_t r, hn::Vec<DF> k) {
  const hn::RebindToSigned<DF> di;
  const auto dk = hn::Sub(k, hn::LoadU(df, t.k_mid.data() + r));
  const auto pb = hn::MulAdd(dk, hn::LoadU(df, t.beta_b.data() + r), hn::LoadU(df, t.pb_mid.data() + r));
  const auto pc = hn::MulAdd(dk, hn::LoadU(df, t.beta_c.data() + r), hn::LoadU(df, t.pc_mid.data() + r));
  const auto fb0 = hn::Floor(pb), fc0 = hn::Floor(pc);
  SamplePosition<DF> s;
  s.ib = hn::Sub(hn::ConvertTo(di, fb0), hn::Set(di, t.origin_b));
  s.ic = hn::Sub(hn::ConvertTo(di, fc0), hn::Set(di, t.origin_c));
  s.fb = hn::Sub(pb, fb0);
  s.fc = hn::Sub(pc, fc0);
  const auto one = hn::Set(df, 1.0f);
  s.gb = hn::Sub(one, s.fb);
  s.gc = hn::Sub(one, s.fc);
  return s;
}

template <class DF>
HWY_INLINE SamplePosition<DF> position_at(DF df, const RayTable& t, std::size_t r, int k) {
  return position_at(df, t, r, hn::Set(df, static_cast<float>(k)));
}

// The bilinear weights of corners (b, c), (b + 1, c), (b, c + 1), (b + 1, c + 1): every path
// (masked, interior, row window, both directions) takes them from here.
template <class DF>
HWY_INLINE void bilinear_weights(const SamplePosition<DF>& p, hn::Vec<DF> (&weight)[4]) {
  weight[0] = hn::Mul(p.gb, p.gc);
  weight[1] = hn::Mul(p.fb, p.gc);
  weight[2] = hn::Mul(p.gb, p.fc);
  weight[3] = hn::Mul(p.fb, p.fc);
}

template <class DF>
HWY_INLINE Corners<DF> corners_at(DF df, const RayTable& t, std::size_t r, int k, hn::Mask<DF> lanes) {
  const hn::RebindToSigned<DF> di;
  using VI = hn::Vec<decltype(di)>;
  const VI vk = hn::Set(di, k);
  const VI k_first = hn::LoadU(di, t.k_first.data() + r), k_last = hn::LoadU(di, t.k_last.data() + r);
  const VI minus_one = hn::Set(di, -1), one_i = hn::Set(di, 1);
  // (Highway 1.0 compares signed lanes with Lt/Gt only.)
  const auto in_range = hn::And(hn::Lt(k_first, hn::Add(vk, one_i)), hn::Lt(vk, hn::Add(k_last, one_i)));
  const auto active = hn::And(lanes, hn::RebindMask(df, in_range));

  const SamplePosition<DF> p = position_at(df, t, r, k);
  const VI ib = p.ib, ic = p.ic;

  const VI nb = hn::LoadU(di, t.n_b.data() + r), nc = hn::LoadU(di, t.n_c.data() + r);
  const VI zero = hn::Zero(di);
  const VI nb1 = hn::Sub(nb, one_i), nc1 = hn::Sub(nc, one_i);
  const VI ib1 = hn::Add(ib, one_i), ic1 = hn::Add(ic, one_i);
  // Corner validity: -1 < index < n.
  const auto vb0 = hn::RebindMask(df, hn::And(hn::Gt(ib, minus_one), hn::Lt(ib, nb)));
  const auto vb1 = hn::RebindMask(df, hn::And(hn::Gt(ib1, minus_one), hn::Lt(ib1, nb)));
  const auto vc0 = hn::RebindMask(df, hn::And(hn::Gt(ic, minus_one), hn::Lt(ic, nc)));
  const auto vc1 = hn::RebindMask(df, hn::And(hn::Gt(ic1, minus_one), hn::Lt(ic1, nc)));

  const VI sa = hn::LoadU(di, t.stride_a.data() + r), sb = hn::LoadU(di, t.stride_b.data() + r),
           sc = hn::LoadU(di, t.stride_c.data() + r);
  const VI base = hn::Mul(hn::Set(di, k - t.origin_a), sa);
  const VI ob0 = hn::Mul(hn::Min(hn::Max(ib, zero), nb1), sb), ob1 = hn::Mul(hn::Min(hn::Max(ib1, zero), nb1), sb);
  const VI oc0 = hn::Mul(hn::Min(hn::Max(ic, zero), nc1), sc), oc1 = hn::Mul(hn::Min(hn::Max(ic1, zero), nc1), sc);

  Corners<DF> out;
  out.index[0] = hn::Add(base, hn::Add(ob0, oc0));
  out.index[1] = hn::Add(base, hn::Add(ob1, oc0));
  out.index[2] = hn::Add(base, hn::Add(ob0, oc1));
  out.index[3] = hn::Add(base, hn::Add(ob1, oc1));
  bilinear_weights(p, out.weight);
  out.weight[0] = hn::IfThenElseZero(hn::And(active, hn::And(vb0, vc0)), out.weight[0]);
  out.weight[1] = hn::IfThenElseZero(hn::And(active, hn::And(vb1, vc0)), out.weight[1]);
  out.weight[2] = hn::IfThenElseZero(hn::And(active, hn::And(vb0, vc1)), out.weight[2]);
  out.weight[3] = hn::IfThenElseZero(hn::And(active, hn::And(vb1, vc1)), out.weight[3]);
  return out;
}

// Same sample as corners_at for lanes known to be well inside the volume (all four corners
// valid) and inside their ray's range: identical arithmetic, no masks.
template <class DF>
HWY_INLINE Corners<DF> interior_corners_at(DF df, const RayTable& t, std::size_t r, int k) {
  const hn::RebindToSigned<DF> di;
  using VI = hn::Vec<decltype(di)>;
  const VI vk = hn::Set(di, k - t.origin_a);
  const SamplePosition<DF> p = position_at(df, t, r, k);
  const VI sb = hn::LoadU(di, t.stride_b.data() + r), sc = hn::LoadU(di, t.stride_c.data() + r);
  const VI i00 = hn::Add(hn::Mul(vk, hn::LoadU(di, t.stride_a.data() + r)), hn::Add(hn::Mul(p.ib, sb), hn::Mul(p.ic, sc)));
  Corners<DF> out;
  out.index[0] = i00;
  out.index[1] = hn::Add(i00, sb);
  out.index[2] = hn::Add(i00, sc);
  out.index[3] = hn::Add(out.index[1], sc);
  bilinear_weights(p, out.weight);
  return out;
}

// Slices where every lane of the bundle (those with `axis`, or all when axis < 0) is inside its
// ray's range with all four corners at least 1e-3 voxel inside the volume: the fast path.
// Empty (lo > hi) when any such lane has none.
HWY_INLINE void interior_range(const RayTable& t, std::size_t r, std::size_t n, int axis, int& lo, int& hi) {
  lo = -(1 << 30);
  hi = 1 << 30;
  for (std::size_t l = 0; l < n; ++l) {
    const std::size_t i = r + l;
    if (axis >= 0 && t.axis[i] != axis) continue;
    if (t.k_last[i] < t.k_first[i]) {  // a ray that misses the volume: no fast path here
      lo = 1 << 30;
      return;
    }
    double k_lo = t.k_first[i], k_hi = t.k_last[i];
    const double margin = 1e-3;
    for (int q = 0; q < 2; ++q) {
      const double p_mid = q == 0 ? t.pb_mid[i] - t.origin_b : t.pc_mid[i] - t.origin_c;
      const double beta = q == 0 ? t.beta_b[i] : t.beta_c[i];
      const double n_max = (q == 0 ? t.n_b[i] : t.n_c[i]) - 1 - margin;
      if (beta == 0) {
        if (!(p_mid >= margin && p_mid <= n_max)) k_lo = 1e9;
        continue;
      }
      double a = t.k_mid[i] + (margin - p_mid) / beta, b = t.k_mid[i] + (n_max - p_mid) / beta;
      if (a > b) std::swap(a, b);
      k_lo = std::max(k_lo, std::ceil(a));
      k_hi = std::min(k_hi, std::floor(b));
    }
    lo = std::max(lo, static_cast<int>(std::max(k_lo, -1e9)));
    hi = std::min(hi, static_cast<int>(std::min(k_hi, 1e9)));
  }
}

// What a kernel needs to know about one bundle of N neighbouring rays before marching it.
struct Bundle {
  std::size_t r = 0;       // first entry
  int k_lo = 0, k_hi = -1;  // slices any lane visits
  int in_lo = 0, in_hi = -1;  // slices on the fast path (interior_range)
  bool pairs = false;      // corners b and b + 1 adjacent in memory for every lane
  bool window = false;     // pairs, one axis for every lane: rows of the slice can be loaded whole
};

// The bundle at entry r, restricted to lanes of dominant `axis` (all lanes when axis < 0).
HWY_INLINE Bundle bundle_at(const RayTable& t, std::size_t r, std::size_t n, int axis) {
  Bundle b;
  b.r = r;
  b.k_lo = 1 << 30;
  b.k_hi = -(1 << 30);
  bool all_on_axis = true;
  b.pairs = true;
  for (std::size_t l = 0; l < n; ++l) {
    const std::size_t i = r + l;
    b.pairs = b.pairs && t.stride_b[i] == 1;
    if (axis >= 0 && t.axis[i] != axis) {
      all_on_axis = false;
      continue;
    }
    if (t.k_last[i] < t.k_first[i]) continue;
    b.k_lo = std::min(b.k_lo, t.k_first[i]);
    b.k_hi = std::max(b.k_hi, t.k_last[i]);
  }
  b.window = b.pairs && n >= 4 && t.n_b[r] >= static_cast<int>(2 * n);
  for (std::size_t l = 1; l < n && b.window; ++l) b.window = t.axis[r + l] == t.axis[r];
  interior_range(t, r, n, axis, b.in_lo, b.in_hi);
  // The fast path needs every lane on the axis (others would touch voxels outside the slab).
  if (!all_on_axis) b.in_lo = 1 << 30;
  return b;
}

// The two floats at volume[index] and volume[index + 1] for every lane, as (first, second): one
// 64-bit gather per pair instead of two 32-bit ones (gathers cost per element loaded).
template <class DF>
HWY_INLINE void gather_pairs(DF df, const float* HWY_RESTRICT volume, hn::Vec<hn::RebindToSigned<DF>> index,
                             hn::Vec<DF>& first, hn::Vec<DF>& second) {
#if HWY_TARGET == HWY_SCALAR
  first = hn::GatherIndex(df, volume, index);
  second = hn::GatherIndex(df, volume, hn::Add(index, hn::Set(hn::RebindToSigned<DF>(), 1)));
#else
  const hn::Repartition<double, DF> dd;
  const hn::RebindToSigned<decltype(dd)> dl;
  const hn::Rebind<std::int32_t, decltype(dd)> dh;
  const auto* base = reinterpret_cast<const double*>(volume);
  const auto lo = hn::BitCast(df, hn::GatherOffset(dd, base, hn::ShiftLeft<2>(hn::PromoteTo(dl, hn::LowerHalf(dh, index)))));
  const auto hi = hn::BitCast(df, hn::GatherOffset(dd, base, hn::ShiftLeft<2>(hn::PromoteTo(dl, hn::UpperHalf(dh, index)))));
  first = hn::ConcatEven(df, hi, lo);
  second = hn::ConcatOdd(df, hi, lo);
#endif
}

// The sample from its four corner values, in the same order on every path.
template <class V>
HWY_INLINE V weigh(V v0, V v1, V v2, V v3, const V (&weight)[4]) {
  return hn::MulAdd(v3, weight[3], hn::MulAdd(v2, weight[2], hn::MulAdd(v1, weight[1], hn::Mul(v0, weight[0]))));
}

// Sum over the four corners of volume value times weight.
template <class DF>
HWY_INLINE hn::Vec<DF> interpolate(DF df, const float* HWY_RESTRICT volume, const Corners<DF>& c) {
  return weigh(hn::GatherIndex(df, volume, c.index[0]), hn::GatherIndex(df, volume, c.index[1]),
               hn::GatherIndex(df, volume, c.index[2]), hn::GatherIndex(df, volume, c.index[3]), c.weight);
}

// The same for interior corners of a bundle whose corners b and b + 1 are adjacent.
template <class DF>
HWY_INLINE hn::Vec<DF> interpolate_pairs(DF df, const float* HWY_RESTRICT volume, const Corners<DF>& c) {
  hn::Vec<DF> v0, v1, v2, v3;
  gather_pairs(df, volume, c.index[0], v0, v1);
  gather_pairs(df, volume, c.index[2], v2, v3);
  return weigh(v0, v1, v2, v3, c.weight);
}

// Lanes of `lo` (pos < N) or `hi` (pos - N otherwise), pos in [0, 2N): a two-table permute.
template <class DF>
HWY_INLINE hn::Vec<DF> lookup_window(DF df, hn::Vec<DF> lo, hn::Vec<DF> hi, hn::Vec<hn::RebindToSigned<DF>> pos) {
#if HWY_TARGET <= HWY_AVX3
  (void)df;
  return hn::Vec<DF>{_mm512_permutex2var_ps(lo.raw, pos.raw, hi.raw)};
#else
  const hn::RebindToSigned<DF> di;
  const auto n = hn::Set(di, static_cast<std::int32_t>(hn::Lanes(df)));
  const auto idx = hn::IndicesFromVec(df, hn::And(pos, hn::Sub(n, hn::Set(di, 1))));
  return hn::IfThenElse(hn::RebindMask(df, hn::Lt(pos, n)), hn::TableLookupLanes(lo, idx), hn::TableLookupLanes(hi, idx));
#endif
}

// Where a window bundle's lanes sit in slice k: the first voxel x0 of the 2N-voxel window along
// b (kept inside the row) and the lower row c0. Lanes are monotone along a detector row, so the
// ends decide; the kernels then check every lane against the window.
template <class DF>
HWY_INLINE void window_origin(DF df, const SamplePosition<DF>& p, int n_b, int& x0, int& c0) {
  const auto last = hn::Lanes(df) - 1;
  const int N = static_cast<int>(hn::Lanes(df));
  x0 = std::min(std::max(std::min(hn::GetLane(p.ib), hn::ExtractLane(p.ib, last)), 0), n_b - 2 * N);
  c0 = std::min(hn::GetLane(p.ic), hn::ExtractLane(p.ic, last));
}

// The interior sample of a window bundle (Bundle::window) without gathers, when its lanes fall in
// a window of 2N voxels along b and at most two neighbouring values of c: the slice's rows
// there are loaded whole and each lane picks its corners by permutes. False (and `sample`
// untouched) when the lanes spread wider; the caller then gathers.
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
  int x0, c0;
  window_origin(df, p, t.n_b[r], x0, c0);
  const auto pos = hn::Sub(p.ib, hn::Set(di, x0)), pos1 = hn::Add(pos, hn::Set(di, 1));
  const auto dc = hn::Sub(p.ic, hn::Set(di, c0));
  const auto limit = hn::Set(di, 2 * N);
  const auto zero = hn::Zero(di), one = hn::Set(di, 1);
  const auto upper = hn::Eq(dc, one);  // lanes whose corner c sits one row up
  if (!hn::AllTrue(di, hn::And(hn::Gt(pos, hn::Set(di, -1)), hn::Lt(pos1, limit))) ||
      !hn::AllTrue(di, hn::Or(hn::Eq(dc, zero), upper)))
    return false;
  const std::ptrdiff_t sc = t.stride_c[r];
  const float* row = volume + static_cast<std::ptrdiff_t>(k - t.origin_a) * t.stride_a[r] + static_cast<std::ptrdiff_t>(c0) * sc + x0;
  const auto r0lo = hn::LoadU(df, row), r0hi = hn::LoadU(df, row + N);
  const auto r1lo = hn::LoadU(df, row + sc), r1hi = hn::LoadU(df, row + sc + N);
  auto c00 = lookup_window(df, r0lo, r0hi, pos), c10 = lookup_window(df, r0lo, r0hi, pos1);
  auto c01 = lookup_window(df, r1lo, r1hi, pos), c11 = lookup_window(df, r1lo, r1hi, pos1);
  if (!hn::AllFalse(di, upper)) {  // some lanes one row up: shift them by a row
    const auto up = hn::RebindMask(df, upper);
    const auto r2lo = hn::LoadU(df, row + 2 * sc), r2hi = hn::LoadU(df, row + 2 * sc + N);
    c00 = hn::IfThenElse(up, c01, c00);
    c10 = hn::IfThenElse(up, c11, c10);
    c01 = hn::IfThenElse(up, lookup_window(df, r2lo, r2hi, pos), c01);
    c11 = hn::IfThenElse(up, lookup_window(df, r2lo, r2hi, pos1), c11);
  }
  hn::Vec<DF> weight[4];
  bilinear_weights(p, weight);
  sample = weigh(c00, c10, c01, c11, weight);
  return true;
#endif
}

#if HWY_TARGET <= HWY_AVX3
// The adjoint of interpolate_window for 16 lanes, without a scatter: each lane's four corner
// weights times `value` are placed at their voxels of a window of 32 voxels along b (expand
// puts lane after lane at the set bits of a mask), in the slice's rows c0 .. c0 + 2, which are
// then updated whole. Lanes on the same voxel (rays closer than a voxel) are first summed
// into one. False (and nothing written) when the lanes spread wider, or three share a voxel.
HWY_INLINE bool scatter_window(const RayTable& t, float* HWY_RESTRICT volume, std::size_t r, int k,
                               hn::Vec<hn::ScalableTag<float>> value) {
  const hn::ScalableTag<float> df;
  const hn::RebindToSigned<decltype(df)> di;
  constexpr int N = 16;
  const auto p = position_at(df, t, r, k);
  int x0, c0;
  window_origin(df, p, t.n_b[r], x0, c0);
  auto pos = hn::Sub(p.ib, hn::Set(di, x0)), dc = hn::Sub(p.ic, hn::Set(di, c0));
  hn::Vec<decltype(df)> bilinear[4];
  bilinear_weights(p, bilinear);
  __m512 w[4];
  for (int q = 0; q < 4; ++q) w[q] = hn::Mul(bilinear[q], value).raw;
  if (hn::ExtractLane(p.ib, N - 1) < hn::GetLane(p.ib)) {  // lanes in increasing b
    pos = hn::Reverse(di, pos), dc = hn::Reverse(di, dc);
    for (auto& v : w) v = hn::Reverse(df, hn::Vec<decltype(df)>{v}).raw;
  }
  const __m512i P = pos.raw, C = dc.raw;
  // Every lane inside the window (with its b + 1 corner) and on row c0 or c0 + 1; b never
  // decreasing from lane to lane.
  const __mmask16 inside = _mm512_cmpge_epi32_mask(P, _mm512_setzero_si512()) &
                           _mm512_cmplt_epi32_mask(P, _mm512_set1_epi32(2 * N - 1)) &
                           _mm512_cmpge_epi32_mask(C, _mm512_setzero_si512()) & _mm512_cmple_epi32_mask(C, _mm512_set1_epi32(1));
  const __m512i P_next = _mm512_alignr_epi32(P, P, 1);  // lane l holds P[l + 1] (l < N - 1)
  if (inside != 0xFFFF || (_mm512_cmpge_epi32_mask(P_next, P) & 0x7FFF) != 0x7FFF) return false;
  // A lane on the same voxel as the lane before it takes that lane's weights; that lane is dropped.
  const __m512i key = _mm512_add_epi32(P, _mm512_slli_epi32(C, 6));
  const __m512i key_prev = _mm512_alignr_epi32(key, _mm512_set1_epi32(-1), 15);  // lane l holds key[l - 1]
  const __mmask16 same_as_prev = _mm512_cmpeq_epi32_mask(key, key_prev);
  if ((same_as_prev & (same_as_prev << 1)) != 0) return false;
  const auto keep = static_cast<__mmask16>(~(same_as_prev >> 1));
  for (auto& v : w) v = _mm512_mask_add_ps(
           v, same_as_prev, v, _mm512_castsi512_ps(_mm512_alignr_epi32(_mm512_castps_si512(v), _mm512_setzero_si512(), 15)));
  // Which lane feeds each of the 32 window voxels: the kept lanes' numbers, in order, expanded
  // to the voxels they occupy (lanes are sorted along b). The weights are then placed with
  // permutes: one compress and two expands per row pair instead of per corner (each costs
  // about five cycles on Zen 5, a permute about two).
  const __m512i lane_number = _mm512_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15);
  const __mmask16 upper = _mm512_cmpeq_epi32_mask(C, _mm512_set1_epi32(1));
  const std::ptrdiff_t sc = t.stride_c[r];
  float* base = volume + static_cast<std::ptrdiff_t>(k - t.origin_a) * t.stride_a[r] + static_cast<std::ptrdiff_t>(c0) * sc + x0;
  for (int layer = 0; layer < 2; ++layer) {  // lanes whose corner c is row c0, then c0 + 1
    const auto lanes = static_cast<__mmask16>(keep & (layer == 0 ? ~upper : upper));
    if (lanes == 0) continue;
    const auto bits = static_cast<std::uint32_t>(
        _mm512_reduce_or_epi32(_mm512_maskz_sllv_epi32(lanes, _mm512_set1_epi32(1), P)));
    const auto bits_lo = static_cast<__mmask16>(bits & 0xFFFFu), bits_hi = static_cast<__mmask16>(bits >> 16);
    const __m512i kept = lanes == 0xFFFF ? lane_number : _mm512_maskz_compress_epi32(lanes, lane_number);
    const __m512i from_lo = _mm512_maskz_expand_epi32(bits_lo, kept);
    const __m512i from_hi = _mm512_maskz_expand_epi32(
        bits_hi, _mm512_permutexvar_epi32(_mm512_add_epi32(lane_number, _mm512_set1_epi32(_mm_popcnt_u32(bits_lo))), kept));
    // Corner b + 1 sits one voxel further: the same map shifted up by one voxel.
    const __m512i from1_lo = _mm512_alignr_epi32(from_lo, _mm512_setzero_si512(), 15);
    const __m512i from1_hi = _mm512_alignr_epi32(from_hi, from_lo, 15);
    const auto bits1 = bits << 1;
    const auto bits1_lo = static_cast<__mmask16>(bits1 & 0xFFFFu), bits1_hi = static_cast<__mmask16>(bits1 >> 16);
    float* row = base + layer * sc;
    for (int q = 0; q < 2; ++q, row += sc) {  // corner c, then c + 1
      const __m512 lo = _mm512_add_ps(_mm512_maskz_permutexvar_ps(bits_lo, from_lo, w[2 * q]),
                                      _mm512_maskz_permutexvar_ps(bits1_lo, from1_lo, w[2 * q + 1]));
      const __m512 hi = _mm512_add_ps(_mm512_maskz_permutexvar_ps(bits_hi, from_hi, w[2 * q]),
                                      _mm512_maskz_permutexvar_ps(bits1_hi, from1_hi, w[2 * q + 1]));
      _mm512_storeu_ps(row, _mm512_add_ps(_mm512_loadu_ps(row), lo));
      _mm512_storeu_ps(row + N, _mm512_add_ps(_mm512_loadu_ps(row + N), hi));
    }
  }
  return true;
}
#endif

// volume[index] += weight * value over the four corners of every lane, lane by lane (lanes
// often share a voxel). A zero weight touches nothing, which also keeps lanes of other axes
// out of voxels outside the slab. (A gather, add and scatter per corner was tried: 1.7x
// slower on Zen 5, the next corner's gather waiting for the scatter's stores.)
template <class DF>
HWY_INLINE void scatter_add(DF df, const Corners<DF>& c, hn::Vec<DF> value, float* HWY_RESTRICT volume) {
  const hn::RebindToSigned<DF> di;
  const int N = static_cast<int>(hn::Lanes(df));
  HWY_ALIGN std::int32_t index[4][kMaxLanes];
  HWY_ALIGN float weight[4][kMaxLanes];
  for (int q = 0; q < 4; ++q) {
    hn::Store(c.index[q], di, index[q]);
    hn::Store(hn::Mul(c.weight[q], value), df, weight[q]);
  }
  for (int l = 0; l < N; ++l)
    for (int q = 0; q < 4; ++q)
      if (weight[q][l] != 0.0f) volume[index[q][l]] += weight[q][l];
}

// The same for interior corners, where every lane is on the slab's axis and every corner inside
// the volume: no test per corner, and corners 1 to 3 are offsets of corner 0.
template <class DF>
HWY_INLINE void scatter_add_interior(DF df, const Corners<DF>& c, hn::Vec<DF> value, float* HWY_RESTRICT volume) {
  const hn::RebindToSigned<DF> di;
  const int N = static_cast<int>(hn::Lanes(df));
  HWY_ALIGN std::int32_t index[kMaxLanes];
  HWY_ALIGN float weight[4][kMaxLanes];
  hn::Store(c.index[0], di, index);
  for (int q = 0; q < 4; ++q) hn::Store(hn::Mul(c.weight[q], value), df, weight[q]);
  const std::int32_t db = hn::GetLane(hn::Sub(c.index[1], c.index[0])), dc = hn::GetLane(hn::Sub(c.index[2], c.index[0]));
  for (int l = 0; l < N; ++l) {
    float* v = volume + index[l];
    v[0] += weight[0][l];
    v[db] += weight[1][l];
    v[dc] += weight[2][l];
    v[db + dc] += weight[3][l];
  }
}

// The forward sum of bundle b over slices [k_lo, k_hi], not yet times the path length.
template <class DF>
HWY_INLINE hn::Vec<DF> march_forward(DF df, const RayTable& t, const float* HWY_RESTRICT volume, const Bundle& b,
                                     int k_lo, int k_hi) {
  const auto all = hn::FirstN(df, hn::Lanes(df));
  auto sum = hn::Zero(df);
  for (int k = k_lo; k <= k_hi; ++k) {
    if (k >= b.in_lo && k <= b.in_hi) {
      hn::Vec<DF> sample;
      if (!b.window || !interpolate_window(df, t, volume, b.r, k, sample)) {
        const auto c = interior_corners_at(df, t, b.r, k);
        sample = b.pairs ? interpolate_pairs(df, volume, c) : interpolate(df, volume, c);
      }
      sum = hn::Add(sum, sample);
    } else {
      sum = hn::Add(sum, interpolate(df, volume, corners_at(df, t, b.r, k, all)));
    }
  }
  return sum;
}

// volume += the adjoint of march_forward for `value` (already times the path length), for the
// lanes in `lanes`.
template <class DF>
HWY_INLINE void march_back(DF df, const RayTable& t, const Bundle& b, hn::Vec<DF> value, hn::Mask<DF> lanes, int k_lo,
                           int k_hi, float* HWY_RESTRICT volume) {
  for (int k = k_lo; k <= k_hi; ++k) {
    if (k >= b.in_lo && k <= b.in_hi) {
#if HWY_TARGET <= HWY_AVX3
      if (b.window && scatter_window(t, volume, b.r, k, value)) continue;
#endif
      scatter_add_interior(df, interior_corners_at(df, t, b.r, k), value, volume);
    } else {
      scatter_add(df, corners_at(df, t, b.r, k, lanes), value, volume);
    }
  }
}

// Rays along x step across the volume's contiguous axis: neighbouring rays' corners are a row
// (y) or a plane (z) apart and have to be gathered one by one. So the bundles of one column
// strip of a table (one per detector row) are marched through a tile instead: the slices of 16
// steps, copied with y contiguous (a transposition), where the row-window paths apply as they
// do to rays along y and z. Voxels outside the volume are zeros in the tile, as the masked
// paths make them. A tile is at most kTileSlices x kTileMaxHeight x kTileMaxWidth floats (96 kB).
constexpr int kTileSlices = 16;
constexpr int kTileMaxWidth = 64, kTileMaxHeight = 24;

struct Tile {
  int k0 = 0, slices = 0;  // x range k0 .. k0 + slices - 1
  int y0 = 0, width = 0;   // y range, contiguous; a multiple of 16 and at least 32
  int z0 = 0, height = 0;  // z range
  float* data = nullptr;   // [slice][z][y]
  std::size_t row(int kk, int zz) const {
    return (static_cast<std::size_t>(kk) * static_cast<std::size_t>(height) + static_cast<std::size_t>(zz)) *
           static_cast<std::size_t>(width);
  }
};

// Where the volume's voxels are for rays along x (their b is y, their c is z).
struct XGrid {
  std::ptrdiff_t stride_y = 0, stride_z = 0;
  int ny = 0, nz = 0;
};

#if HWY_TARGET <= HWY_AVX3
// In place: row j of the input becomes column j.
HWY_INLINE void transpose16(__m512 (&r)[16]) {
  __m512 t[16];
  for (int i = 0; i < 8; ++i) {
    t[2 * i] = _mm512_unpacklo_ps(r[2 * i], r[2 * i + 1]);
    t[2 * i + 1] = _mm512_unpackhi_ps(r[2 * i], r[2 * i + 1]);
  }
  const auto lo64 = [](__m512 a, __m512 b) {
    return _mm512_castpd_ps(_mm512_unpacklo_pd(_mm512_castps_pd(a), _mm512_castps_pd(b)));
  };
  const auto hi64 = [](__m512 a, __m512 b) {
    return _mm512_castpd_ps(_mm512_unpackhi_pd(_mm512_castps_pd(a), _mm512_castps_pd(b)));
  };
  for (int i = 0; i < 4; ++i) {  // r[4i + j]: rows 4i .. 4i + 3 of column j of each 4-column block
    r[4 * i] = lo64(t[4 * i], t[4 * i + 2]);
    r[4 * i + 1] = hi64(t[4 * i], t[4 * i + 2]);
    r[4 * i + 2] = lo64(t[4 * i + 1], t[4 * i + 3]);
    r[4 * i + 3] = hi64(t[4 * i + 1], t[4 * i + 3]);
  }
  for (int i = 0; i < 4; ++i) {
    t[i] = _mm512_shuffle_f32x4(r[i], r[4 + i], 0x88);
    t[4 + i] = _mm512_shuffle_f32x4(r[i], r[4 + i], 0xdd);
    t[8 + i] = _mm512_shuffle_f32x4(r[8 + i], r[12 + i], 0x88);
    t[12 + i] = _mm512_shuffle_f32x4(r[8 + i], r[12 + i], 0xdd);
  }
  for (int i = 0; i < 4; ++i) {
    r[i] = _mm512_shuffle_f32x4(t[i], t[8 + i], 0x88);
    r[8 + i] = _mm512_shuffle_f32x4(t[i], t[8 + i], 0xdd);
    r[4 + i] = _mm512_shuffle_f32x4(t[4 + i], t[12 + i], 0x88);
    r[12 + i] = _mm512_shuffle_f32x4(t[4 + i], t[12 + i], 0xdd);
  }
}
#endif

// tile = the volume in the tile's box (zero outside the volume).
HWY_INLINE void fill_tile(const float* HWY_RESTRICT volume, const XGrid& g, const Tile& tile) {
  for (int zz = 0; zz < tile.height; ++zz) {
    const int z = tile.z0 + zz;
    const bool z_in = z >= 0 && z < g.nz;
#if HWY_TARGET <= HWY_AVX3
    const auto slices = static_cast<__mmask16>((1u << tile.slices) - 1u);
    for (int yb = 0; yb < tile.width; yb += 16) {
      __m512 r[16];
      for (int j = 0; j < 16; ++j) {
        const int y = tile.y0 + yb + j;
        if (!z_in || y < 0 || y >= g.ny) {
          r[j] = _mm512_setzero_ps();
          continue;
        }
        const float* x_row = volume + tile.k0 + y * g.stride_y + z * g.stride_z;
        r[j] = _mm512_maskz_loadu_ps(slices, x_row);
        // The strip's next tile reads the next 16 voxels of the same rows: each row is its own
        // stream, too many for the hardware prefetcher to follow.
        _mm_prefetch(reinterpret_cast<const char*>(x_row + kTileSlices), _MM_HINT_T0);
      }
      transpose16(r);
      for (int kk = 0; kk < tile.slices; ++kk) _mm512_storeu_ps(tile.data + tile.row(kk, zz) + yb, r[kk]);
    }
#else
    for (int kk = 0; kk < tile.slices; ++kk)
      for (int yy = 0; yy < tile.width; ++yy) {
        const int y = tile.y0 + yy;
        tile.data[tile.row(kk, zz) + static_cast<std::size_t>(yy)] =
            z_in && y >= 0 && y < g.ny ? volume[tile.k0 + kk + y * g.stride_y + z * g.stride_z] : 0.0f;
      }
#endif
  }
}

// volume += tile, inside the volume.
HWY_INLINE void add_tile(const Tile& tile, const XGrid& g, float* HWY_RESTRICT volume) {
  for (int zz = 0; zz < tile.height; ++zz) {
    const int z = tile.z0 + zz;
    if (z < 0 || z >= g.nz) continue;
#if HWY_TARGET <= HWY_AVX3
    const auto slices = static_cast<__mmask16>((1u << tile.slices) - 1u);
    for (int yb = 0; yb < tile.width; yb += 16) {
      __m512 r[16];
      for (int kk = 0; kk < 16; ++kk)
        r[kk] = kk < tile.slices ? _mm512_loadu_ps(tile.data + tile.row(kk, zz) + yb) : _mm512_setzero_ps();
      transpose16(r);
      for (int j = 0; j < 16; ++j) {
        const int y = tile.y0 + yb + j;
        if (y < 0 || y >= g.ny) continue;
        float* v = volume + tile.k0 + y * g.stride_y + z * g.stride_z;
        _mm512_mask_storeu_ps(v, slices, _mm512_add_ps(_mm512_maskz_loadu_ps(slices, v), r[j]));
      }
    }
#else
    for (int kk = 0; kk < tile.slices; ++kk)
      for (int yy = 0; yy < tile.width; ++yy) {
        const int y = tile.y0 + yy;
        if (y >= 0 && y < g.ny)
          volume[tile.k0 + kk + y * g.stride_y + z * g.stride_z] += tile.data[tile.row(kk, zz) + static_cast<std::size_t>(yy)];
      }
#endif
  }
}

// A bundle whose rays (those that meet the volume, at least one) all run along x.
HWY_INLINE bool along_x(const RayTable& t, std::size_t r, std::size_t n) {
  bool any = false;
  for (std::size_t l = 0; l < n; ++l) {
    if (t.k_last[r + l] < t.k_first[r + l]) continue;
    if (t.axis[r + l] != 0) return false;
    any = true;
  }
  return any;
}

enum class TileFit { nothing, fits, too_large };

// The box of voxels (corners included) the lanes at entries[0 .. count) of `t` touch in slices
// [k0, k1], as the tile's y and z ranges; nothing when no lane has a sample there.
template <class DF>
HWY_INLINE TileFit tile_box(DF df, const RayTable& t, const std::size_t* entries, int count, int k0, int k1, Tile& tile) {
  const hn::RebindToSigned<DF> di;
  constexpr int kFar = 1 << 30;
  auto lo_b = hn::Set(di, kFar), hi_b = hn::Set(di, -kFar), lo_c = lo_b, hi_c = hi_b;
  for (int i = 0; i < count; ++i) {
    const std::size_t r = entries[i];
    const auto ka = hn::Max(hn::LoadU(di, t.k_first.data() + r), hn::Set(di, k0));
    const auto kb = hn::Min(hn::LoadU(di, t.k_last.data() + r), hn::Set(di, k1));
    const auto valid = hn::Lt(ka, hn::Add(kb, hn::Set(di, 1)));
    // The sample moves linearly with k: its ends bound it. Same arithmetic as the kernels.
    const auto pa = position_at(df, t, r, hn::ConvertTo(df, ka)), pb = position_at(df, t, r, hn::ConvertTo(df, kb));
    lo_b = hn::IfThenElse(valid, hn::Min(lo_b, hn::Min(pa.ib, pb.ib)), lo_b);
    hi_b = hn::IfThenElse(valid, hn::Max(hi_b, hn::Max(pa.ib, pb.ib)), hi_b);
    lo_c = hn::IfThenElse(valid, hn::Min(lo_c, hn::Min(pa.ic, pb.ic)), lo_c);
    hi_c = hn::IfThenElse(valid, hn::Max(hi_c, hn::Max(pa.ic, pb.ic)), hi_c);
  }
  const int y0 = hn::GetLane(hn::MinOfLanes(di, lo_b)), y1 = hn::GetLane(hn::MaxOfLanes(di, hi_b)) + 1;
  const int z0 = hn::GetLane(hn::MinOfLanes(di, lo_c)), z1 = hn::GetLane(hn::MaxOfLanes(di, hi_c)) + 1;
  if (y1 < y0) return TileFit::nothing;
  tile.y0 = y0;
  tile.width = std::max(32, (y1 - y0 + 16) / 16 * 16);
  tile.z0 = z0;
  tile.height = z1 - z0 + 1;
  return tile.width <= kTileMaxWidth && tile.height <= kTileMaxHeight ? TileFit::fits : TileFit::too_large;
}

// The copies of a column strip's bundles (in `local`, one row each) address the tile.
HWY_INLINE void address_tile(RayTable& local, int count, const Tile& tile) {
  local.origin_a = tile.k0;
  local.origin_b = tile.y0;
  local.origin_c = tile.z0;
  const std::size_t n = static_cast<std::size_t>(count) * static_cast<std::size_t>(local.row_stride);
  std::fill_n(local.stride_a.begin(), n, tile.width * tile.height);
  std::fill_n(local.stride_b.begin(), n, 1);
  std::fill_n(local.stride_c.begin(), n, tile.width);
  std::fill_n(local.n_b.begin(), n, tile.width);
  std::fill_n(local.n_c.begin(), n, tile.height);
}

// One column strip's bundles along x, and how each is marched through a tile or (where the
// tile would be too large) through the volume.
struct XStrip {
  static constexpr int kMaxBundles = 64;
  int count = 0;
  std::size_t entries[kMaxBundles];  // in the table
  Bundle tile[kMaxBundles];          // the same bundles in `local`, addressing the tile
  int k_lo = 0, k_hi = -1;           // slices any of them visits
  // The same bundles in the volume (for tiles too large), found when first needed.
  Bundle volume[kMaxBundles];
  bool volume_found = false;
};

// Copies the strip's bundles into `local` (row i for bundle i) and finds where they march.
template <class DF>
HWY_INLINE void prepare_strip(DF df, const RayTable& t, XStrip& s, RayTable& local) {
  const std::size_t n = hn::Lanes(df);
  s.k_lo = 1 << 30;
  s.k_hi = -(1 << 30);
  for (int i = 0; i < s.count; ++i) {
    const std::size_t r = s.entries[i];
    Bundle& b = s.tile[i];
    b.r = local.entry(0, i, 0);
    local.copy_entries(t, r, b.r, n);
    b.k_lo = b.in_lo = 1 << 30;
    b.k_hi = b.in_hi = -(1 << 30);
    for (std::size_t l = 0; l < n; ++l) {
      const int first = t.k_first[r + l], last = t.k_last[r + l];
      // In a tile every corner of a lane in its range is there: the fast path needs only that
      // every lane be in its range.
      b.in_lo = std::max(b.in_lo, first);
      b.in_hi = std::min(b.in_hi, last);
      if (last < first) continue;
      b.k_lo = std::min(b.k_lo, first);
      b.k_hi = std::max(b.k_hi, last);
    }
    b.pairs = true;
    b.window = n >= 4;
    s.k_lo = std::min(s.k_lo, b.k_lo);
    s.k_hi = std::max(s.k_hi, b.k_hi);
  }
  s.volume_found = false;
}

HWY_INLINE const Bundle* volume_bundles(const RayTable& t, std::size_t lanes, int axis, XStrip& s) {
  if (!s.volume_found)
    for (int i = 0; i < s.count; ++i) s.volume[i] = bundle_at(t, s.entries[i], lanes, axis);
  s.volume_found = true;
  return s.volume;
}

HWY_INLINE XGrid x_grid(const RayTable& t, std::size_t r) {
  return {t.stride_b[r], t.stride_c[r], t.n_b[r], t.n_c[r]};
}

// Slices [k_begin, k_end) in chunks of up to kTileSlices, aligned so that each tile row is one
// cache line where the slab allows.
template <class F>
HWY_INLINE void for_each_chunk(int k_lo, int k_hi, int k_begin, int k_end, F&& f) {
  const int lo = std::max(k_lo, k_begin), hi = std::min(k_hi, k_end - 1);
  for (int k0 = lo / kTileSlices * kTileSlices; k0 <= hi; k0 += kTileSlices)
    f(std::max(k0, lo), std::min(k0 + kTileSlices - 1, hi));
}

template <class DF>
HWY_INLINE void forward_strip(DF df, const RayTable& t, const float* HWY_RESTRICT volume, XStrip& s, RayTable& local,
                              float* tile_data, float* HWY_RESTRICT out) {
  prepare_strip(df, t, s, local);
  HWY_ALIGN float sums[XStrip::kMaxBundles * kMaxLanes] = {};
  const XGrid g = x_grid(t, s.entries[0]);
  Tile tile;
  tile.data = tile_data;
  for_each_chunk(s.k_lo, s.k_hi, 0, 1 << 30, [&](int k0, int k1) {
    const TileFit fit = tile_box(df, t, s.entries, s.count, k0, k1, tile);
    if (fit == TileFit::nothing) return;
    if (fit == TileFit::fits) {
      tile.k0 = k0;
      tile.slices = k1 - k0 + 1;
      fill_tile(volume, g, tile);
      address_tile(local, s.count, tile);
    }
    const Bundle* in_volume = fit == TileFit::fits ? nullptr : volume_bundles(t, hn::Lanes(df), -1, s);
    for (int i = 0; i < s.count; ++i) {
      const Bundle& b = in_volume ? in_volume[i] : s.tile[i];
      const auto sum = in_volume ? march_forward(df, t, volume, b, std::max(k0, b.k_lo), std::min(k1, b.k_hi))
                                 : march_forward(df, local, tile.data, b, std::max(k0, b.k_lo), std::min(k1, b.k_hi));
      float* acc = sums + i * kMaxLanes;
      hn::Store(hn::Add(hn::Load(df, acc), sum), df, acc);
    }
  });
  for (int i = 0; i < s.count; ++i) {
    const std::size_t r = s.entries[i];
    hn::StoreU(hn::Mul(hn::Load(df, sums + i * kMaxLanes), hn::LoadU(df, t.weight.data() + r)), df, out + r);
  }
}

template <class DF>
HWY_INLINE void back_strip(DF df, const RayTable& t, int k_begin, int k_end, XStrip& s, RayTable& local,
                           float* tile_data, float* HWY_RESTRICT volume) {
  prepare_strip(df, t, s, local);
  const auto all = hn::FirstN(df, hn::Lanes(df));
  const XGrid g = x_grid(t, s.entries[0]);
  Tile tile;
  tile.data = tile_data;
  for_each_chunk(s.k_lo, s.k_hi, k_begin, k_end, [&](int k0, int k1) {
    const TileFit fit = tile_box(df, t, s.entries, s.count, k0, k1, tile);
    if (fit == TileFit::nothing) return;
    if (fit == TileFit::fits) {
      tile.k0 = k0;
      tile.slices = k1 - k0 + 1;
      std::fill_n(tile.data, tile.row(tile.slices, 0), 0.0f);
      address_tile(local, s.count, tile);
    }
    const Bundle* in_volume = fit == TileFit::fits ? nullptr : volume_bundles(t, hn::Lanes(df), 0, s);
    for (int i = 0; i < s.count; ++i) {
      const std::size_t r = s.entries[i];
      const auto value = hn::Mul(hn::LoadU(df, t.value.data() + r), hn::LoadU(df, t.weight.data() + r));
      if (!in_volume) {
        const Bundle& b = s.tile[i];
        march_back(df, local, b, value, all, std::max(k0, b.k_lo), std::min(k1, b.k_hi), tile.data);
      } else {
        const Bundle& b = in_volume[i];
        const auto on_axis = hn::RebindMask(df, hn::Eq(hn::LoadU(hn::RebindToSigned<DF>(), t.axis.data() + r),
                                                       hn::Zero(hn::RebindToSigned<DF>())));
        march_back(df, t, b, value, on_axis, std::max(k0, b.k_lo), std::min(k1, b.k_hi), volume);
      }
    }
    if (fit == TileFit::fits) add_tile(tile, g, volume);
  });
}

// Bundles go one at a time, every slice of one before the next, except rays along x (above).
// (Marching the bundles of a column strip in consecutive rows together, slice by slice, through
// the volume itself was tried for locality: 25 % slower, the per-sample state no longer
// staying in registers.)
void ForwardRays(const RayTable& t, const float* HWY_RESTRICT volume, float* HWY_RESTRICT out) {
  const hn::ScalableTag<float> df;
  const int N = static_cast<int>(hn::Lanes(df));
  RayTable local;
  local.shape(1, std::min(t.rows, XStrip::kMaxBundles), N);
  std::vector<float> tile_data(static_cast<std::size_t>(kTileSlices * kTileMaxHeight * kTileMaxWidth));
  XStrip strip;
  for (int slot = 0; slot < t.views; ++slot) {
    for (int col = 0; col < t.row_stride; col += N) {
      strip.count = 0;
      for (int row = 0; row < t.rows; ++row) {
        const std::size_t r = t.entry(slot, row, col);
        if (strip.count < XStrip::kMaxBundles && along_x(t, r, static_cast<std::size_t>(N))) {
          strip.entries[strip.count++] = r;
          continue;
        }
        const Bundle b = bundle_at(t, r, static_cast<std::size_t>(N), -1);
        hn::StoreU(hn::Mul(march_forward(df, t, volume, b, b.k_lo, b.k_hi), hn::LoadU(df, t.weight.data() + r)), df,
                   out + r);
      }
      if (strip.count > 0) forward_strip(df, t, volume, strip, local, tile_data.data(), out);
    }
  }
}

void BackRays(const RayTable& t, int axis, int k_begin, int k_end, float* HWY_RESTRICT volume) {
  const hn::ScalableTag<float> df;
  const hn::RebindToSigned<decltype(df)> di;
  const int N = static_cast<int>(hn::Lanes(df));
  RayTable local;
  std::vector<float> tile_data;
  if (axis == 0) {
    local.shape(1, std::min(t.rows, XStrip::kMaxBundles), N);
    tile_data.resize(static_cast<std::size_t>(kTileSlices * kTileMaxHeight * kTileMaxWidth));
  }
  XStrip strip;
  for (int slot = 0; slot < t.views; ++slot) {
    for (int col = 0; col < t.row_stride; col += N) {
      strip.count = 0;
      for (int row = 0; row < t.rows; ++row) {
        const std::size_t r = t.entry(slot, row, col);
        const auto on_axis = hn::RebindMask(df, hn::Eq(hn::LoadU(di, t.axis.data() + r), hn::Set(di, axis)));
        if (hn::AllFalse(df, on_axis)) continue;
        if (axis == 0 && strip.count < XStrip::kMaxBundles && along_x(t, r, static_cast<std::size_t>(N))) {
          strip.entries[strip.count++] = r;
          continue;
        }
        const Bundle b = bundle_at(t, r, static_cast<std::size_t>(N), axis);
        const auto value = hn::Mul(hn::LoadU(df, t.value.data() + r), hn::LoadU(df, t.weight.data() + r));
        march_back(df, t, b, value, on_axis, std::max(b.k_lo, k_begin), std::min(b.k_hi, k_end - 1), volume);
      }
      if (strip.count > 0) back_strip(df, t, k_begin, k_end, strip, local, tile_data.data(), volume);
    }
  }
}

const char* TargetName() { return hwy::TargetName(HWY_TARGET); }
int FloatLanes() { return static_cast<int>(hn::Lanes(hn::ScalableTag<float>())); }

}  // namespace HWY_NAMESPACE
}  // namespace ctk::detail
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
namespace ctk::detail {
HWY_EXPORT(ForwardRays);
HWY_EXPORT(BackRays);
HWY_EXPORT(TargetName);
HWY_EXPORT(FloatLanes);

void forward_rays(const RayTable& t, const float* volume, float* out) { HWY_DYNAMIC_DISPATCH(ForwardRays)(t, volume, out); }
void back_rays(const RayTable& t, int axis, int k_begin, int k_end, float* volume) {
  HWY_DYNAMIC_DISPATCH(BackRays)(t, axis, k_begin, k_end, volume);
}
const char* simd_target_name() { return HWY_DYNAMIC_DISPATCH(TargetName)(); }
int simd_float_lanes() { return HWY_DYNAMIC_DISPATCH(FloatLanes)(); }
}  // namespace ctk::detail
#endif

// Per SIMD target: the back projection's bands. A band is a private copy of the part of a few
// slices that a group of bundles writes, laid out so that each sample's four corners are four
// neighbouring floats: one 128-bit addition per sample instead of two pairs. The band is then
// added to the volume once.
#if defined(CTK_PROJ_JOSEPH_BANDS_INL_H_) == defined(HWY_TARGET_TOGGLE)
#ifdef CTK_PROJ_JOSEPH_BANDS_INL_H_
#undef CTK_PROJ_JOSEPH_BANDS_INL_H_
#else
#define CTK_PROJ_JOSEPH_BANDS_INL_H_
#endif

#include <hwy/highway.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "joseph_samples-inl.h"
#include "joseph_tiles-inl.h"
#include "ray_table.hpp"

HWY_BEFORE_NAMESPACE();
namespace ctk::detail {
namespace HWY_NAMESPACE {
namespace hn = hwy::HWY_NAMESPACE;

// The scatter into the volume adds two pairs of floats per sample (rows c and c + 1), and on the
// Zen 5 each 8-byte store costs about a cycle (benchmarks/paired.py): the stores bound it. A band stores
// every row pair (c, c + 1) of its box interleaved, float by float, so that a sample's corners
// (b, c), (b, c + 1), (b + 1, c), (b + 1, c + 1) are four consecutive floats. As c may be even
// or odd, it holds two such copies: parity 0 interleaves rows (2j, 2j + 1), parity 1 rows
// (2j - 1, 2j) (its row 0 is half outside the box and stays zero). A voxel is in both, once in
// each, and add_band sums them. In a scratch loop over cached data (benchmarks/paired.py) the quads' pass
// took 1.25-1.6 cycles per sample, the pairs' 2.3-2.9.
struct QuadBand {
  int k0 = 0, slices = 0;  // slices k0 .. k0 + slices - 1 of the bundles' axis
  int b0 = 0, width = 0;   // voxels b0 .. b0 + width - 1 along b (the slice's rows)
  int c0 = 0, height = 0;  // rows c0 .. c0 + height - 1
  std::size_t row_floats = 0, parity_floats = 0, slice_floats = 0;
  float* data = nullptr;

  // The layout for the box, with `lanes` floats of spare at each row's end (add_band reads
  // whole vectors); the floats it takes.
  std::size_t lay_out(int lanes) {
    row_floats = 2 * static_cast<std::size_t>((width + lanes - 1) / lanes * lanes + lanes);
    parity_floats = static_cast<std::size_t>(height / 2 + 1) * row_floats;
    slice_floats = 2 * parity_floats;
    return slice_floats * static_cast<std::size_t>(slices);
  }
  // Where the quad of the sample with lower corner (bb, cc) of slice kk (box coordinates) starts.
  std::size_t quad(int kk, int cc, int bb) const {
    return static_cast<std::size_t>(kk) * slice_floats + static_cast<std::size_t>(cc & 1) * parity_floats +
           static_cast<std::size_t>((cc + 1) >> 1) * row_floats + 2 * static_cast<std::size_t>(bb);
  }
  // Row cc of slice kk (box coordinates), floats from bb: its voxels as they sit in the two copies
  // (first float of each pair in one, second in the other).
  const float* first_of_pairs(int kk, int cc, int bb) const { return data + quad(kk, cc, bb); }
  const float* second_of_pairs(int kk, int cc, int bb) const {
    return data + static_cast<std::size_t>(kk) * slice_floats + static_cast<std::size_t>(1 - (cc & 1)) * parity_floats +
           static_cast<std::size_t>(cc >> 1) * row_floats + 2 * static_cast<std::size_t>(bb) + 1;
  }
#if HWY_TARGET != HWY_SCALAR
  // Voxels bb .. bb + Lanes(d) - 1 of row cc of slice kk.
  template <class D>
  HWY_INLINE hn::Vec<D> load(D d, int kk, int cc, int bb) const {
    const std::size_t n = hn::Lanes(d);
    const float* p = first_of_pairs(kk, cc, bb);
    const float* q = second_of_pairs(kk, cc, bb) - 1;
    return hn::Add(hn::ConcatEven(d, hn::LoadU(d, p + n), hn::LoadU(d, p)),
                   hn::ConcatOdd(d, hn::LoadU(d, q + n), hn::LoadU(d, q)));
  }
#endif
  float at(int kk, int cc, int bb) const { return *first_of_pairs(kk, cc, bb) + *second_of_pairs(kk, cc, bb); }
};

// Bands larger than this many floats (1 MB, each thread's own) are not used; their bundles
// scatter as before. In circular views some bands along x are 20-32 rows of z tall (16 slices,
// up to about 150 k floats): with 96 k, 164 of 512 groups of a half-scale run went strip by strip,
// and the standard problem's back projection gained 1.10x instead of 1.24x (benchmarks/paired.py). With
// spherical views in slab order (slab_lines.hpp), bands along y and z of 40-55 rows (8 slices,
// the whole width: 170-230 k floats) gather 1.1-2.2 samples per voxel; 256 k rather than 160 k
// made the spherical back projection 1.06-1.07x faster, circular 1.00x (192 k 1.035x, 384 k
// 1.06x; in-process, benchmarks/paired.py).
inline constexpr std::size_t kMaxBandFloats = 256 * 1024;
// Nor bands with fewer samples than voxels: zeroing a band and adding it back cost about what a
// voxel's samples save. Without this limit spherical views lost 5 %; with 0.5, 1 or 2 samples per
// voxel, in-process: circular 1.30, 1.31, 1.24x, spherical 0.97, 0.98, 0.98x (benchmarks/paired.py).
inline constexpr double kMinSamplesPerVoxel = 1.0;

enum class BandFit { nothing, fits, no };

#if HWY_TARGET != HWY_SCALAR  // a quad is a 128-bit vector

// The box that bundles[0, count) touch in slices [k0, k1] (their lanes in range, corners
// included), in `band`; whether a band there pays (kMaxBandFloats, kMinSamplesPerVoxel).
template <class DF>
HWY_INLINE BandFit band_box(DF df, const RayTable& t, const Bundle* bundles, std::size_t count, int k0, int k1, QuadBand& band) {
  SampleBox<DF> box(df);
  std::int64_t bundle_slices = 0;
  // `band` on the box so far; the floats it takes.
  const auto place = [&] {
    band.k0 = k0;
    band.slices = k1 - k0 + 1;
    band.b0 = box.b_lo();
    band.width = box.b_hi() + 2 - band.b0;
    band.c0 = box.c_lo();
    band.height = box.c_hi() + 2 - band.c0;
    return band.lay_out(static_cast<int>(hn::Lanes(df)));
  };
  for (std::size_t i = 0; i < count; ++i) {
    // The box only grows: once it takes more than kMaxBandFloats, the rest need not be seen
    // (spherical views' tables, whose views look at different parts of the volume, mostly stop
    // here; measuring every bundle's box was 3-6 % of their slab tasks).
    if (i % 32 == 31 && bundle_slices > 0 && place() > kMaxBandFloats) return BandFit::no;
    const Bundle& b = bundles[i];
    const int first = std::max(k0, b.k_lo), last = std::min(k1, b.k_hi);
    if (first > last) continue;
    bundle_slices += last - first + 1;
    box.add(df, t, b.r, k0, k1);
  }
  if (bundle_slices == 0 || box.b_hi() < box.b_lo()) return BandFit::nothing;
  const std::size_t floats = place();
  const double samples = static_cast<double>(bundle_slices) * static_cast<double>(hn::Lanes(df));
  const double voxels = static_cast<double>(band.width) * band.height * band.slices;
  return floats <= kMaxBandFloats && samples >= kMinSamplesPerVoxel * voxels ? BandFit::fits : BandFit::no;
}

// The samples of up to kInteriorBatch slices of one bundle into a band, in two passes as
// InteriorScatter: quads() finds each sample's quad and its four weights (times `value`), add()
// adds them. Interior slices (every lane in range, every corner in the volume) take the plain
// arithmetic; the others MaskedSample's, whose corners outside the volume weigh zero and whose
// lanes out of range add zero to the band's first quad. A lane's corners are always inside the
// band (band_box), also those outside the volume, which add_band leaves out.
template <class DF>
struct QuadScatter {
  HWY_ALIGN std::int32_t index[kInteriorBatch][kMaxLanes];
  HWY_ALIGN float weight[kInteriorBatch][4 * kMaxLanes];  // lane l's quad at (l % 4) N + 4 (l / 4)
  int count = 0;

  HWY_INLINE void quads(DF df, const RayTable& t, const Bundle& bundle, int k0, int slices, hn::Vec<DF> value,
                        const QuadBand& band) {
    const hn::RebindToSigned<DF> di;
    const hn::Repartition<double, DF> dd;
    const std::size_t N = hn::Lanes(df);
    count = slices;
    const BundlePosition<DF> position(df, t, bundle.r);
    const auto b0 = hn::Set(di, band.b0), c0 = hn::Set(di, band.c0), one = hn::Set(di, 1);
    const auto parity_floats = hn::Set(di, static_cast<std::int32_t>(band.parity_floats));
    const auto row_floats = hn::Set(di, static_cast<std::int32_t>(band.row_floats));
    const auto all = hn::FirstN(df, N);
    for (int i = 0; i < count; ++i) {
      const int k = k0 + i;
      SamplePosition<DF> p;
      hn::Vec<DF> w[4];
      auto active = all;
      if (k >= bundle.in_lo && k <= bundle.in_hi) {
        p = position.at(df, k);
        bilinear_weights(p, w);
      } else {
        const MaskedSample<DF> m(df, t, bundle.r, k, all);
        p = m.p;
        active = m.active;
        m.weights(w);
      }
      // QuadBand::quad in SIMD.
      const auto bb = hn::Sub(p.ib, b0), cc = hn::Sub(p.ic, c0);
      const auto at = hn::Add(hn::Set(di, static_cast<std::int32_t>(static_cast<std::size_t>(k - band.k0) * band.slice_floats)),
                              hn::Add(hn::Mul(hn::And(cc, one), parity_floats),
                                      hn::Add(hn::Mul(hn::ShiftRight<1>(hn::Add(cc, one)), row_floats), hn::Add(bb, bb))));
      hn::Store(hn::IfThenElseZero(hn::RebindMask(di, active), at), di, index[i]);
      for (auto& wq : w) wq = hn::Mul(wq, value);
      // The quads (w0, w2, w1, w3) of lanes 4m .. 4m + 3 of each 128-bit block.
      const auto lo = hn::BitCast(dd, hn::InterleaveLower(df, w[0], w[2])),
                 hi = hn::BitCast(dd, hn::InterleaveUpper(df, w[0], w[2]));
      const auto lo1 = hn::BitCast(dd, hn::InterleaveLower(df, w[1], w[3])),
                 hi1 = hn::BitCast(dd, hn::InterleaveUpper(df, w[1], w[3]));
      float* out = weight[i];
      hn::Store(hn::BitCast(df, hn::InterleaveLower(dd, lo, lo1)), df, out);
      hn::Store(hn::BitCast(df, hn::InterleaveUpper(dd, lo, lo1)), df, out + N);
      hn::Store(hn::BitCast(df, hn::InterleaveLower(dd, hi, hi1)), df, out + 2 * N);
      hn::Store(hn::BitCast(df, hn::InterleaveUpper(dd, hi, hi1)), df, out + 3 * N);
    }
  }

  // Slice by slice, even lanes of slice i and then odd lanes of slice i - 1, as the pairs on
  // AVX-512 (InteriorScatter::add): lanes sharing floats are far apart.
  HWY_INLINE void add(DF df, float* HWY_RESTRICT band) const {
    const int N = static_cast<int>(hn::Lanes(df));
    const hn::Full128<float> d4;
    const auto lane = [&](int i, int l) {
      float* v = band + index[i][l];
      hn::StoreU(hn::Add(hn::LoadU(d4, v), hn::LoadU(d4, weight[i] + (l % 4) * N + 4 * (l / 4))), d4, v);
    };
    for (int i = 0; i <= count; ++i) {
      if (i < count)
        for (int m = 0; m < N / 2; ++m) lane(i, 2 * m);
      if (i > 0)
        for (int m = 0; m < N / 2; ++m) lane(i - 1, 2 * m + 1);
    }
  }
};

// The band (its box from band_box) zeroed in `storage`, then bundles[0, count)'s samples in its
// slices added to it, each bundle's projection value times its path length.
template <class DF>
HWY_INLINE void scatter_into_band(DF df, const RayTable& t, const Bundle* bundles, std::size_t count, QuadBand& band,
                                  std::vector<float>& storage) {
  const std::size_t floats = band.slice_floats * static_cast<std::size_t>(band.slices);
  if (storage.size() < floats) storage.resize(floats);
  band.data = storage.data();
  std::fill_n(band.data, floats, 0.0f);
  QuadScatter<DF> scatter;
  const int k1 = band.k0 + band.slices - 1;
  for (std::size_t i = 0; i < count; ++i) {
    const Bundle& b = bundles[i];
    const int first = std::max(band.k0, b.k_lo), last = std::min(k1, b.k_hi);
    const auto value = hn::Mul(hn::LoadU(df, t.value.data() + b.r), hn::LoadU(df, t.weight.data() + b.r));
    for (int k = first; k <= last; k += kInteriorBatch) {
      scatter.quads(df, t, b, k, std::min(kInteriorBatch, last - k + 1), value, band);
      scatter.add(df, band.data);
    }
  }
}

// Bundles in groups of equal key, each group's bundles in their given order.
class BundleGroups {
 public:
  // Sorts bundles[0, count) by key(bundle), an int. The keys span a few groups, so they are
  // counted (std::sort of the pairs took 1.8 % of a spherical back projection, benchmarks/paired.py).
  template <class Key>
  void sort(const Bundle* bundles, std::size_t count, Key&& key) {
    key_.resize(count);
    int lo = 0, hi = -1;
    for (std::size_t i = 0; i < count; ++i) {
      key_[i] = key(bundles[i]);
      lo = i == 0 ? key_[i] : std::min(lo, key_[i]);
      hi = i == 0 ? key_[i] : std::max(hi, key_[i]);
    }
    // Group g's bundles at sorted_[start_[g], start_[g + 1]).
    start_.assign(static_cast<std::size_t>(hi - lo + 2), 0);
    for (const int k : key_) ++start_[static_cast<std::size_t>(k - lo + 1)];
    for (std::size_t g = 1; g < start_.size(); ++g) start_[g] += start_[g - 1];
    sorted_.resize(count);
    next_.assign(start_.begin(), start_.end() - 1);
    for (std::size_t i = 0; i < count; ++i) sorted_[next_[static_cast<std::size_t>(key_[i] - lo)]++] = bundles[i];
  }
  // f(members, count) for each group in turn, its bundles contiguous.
  template <class F>
  void for_each(F&& f) const {
    for (std::size_t g = 0; g + 1 < start_.size(); ++g)
      if (start_[g + 1] > start_[g]) f(sorted_.data() + start_[g], start_[g + 1] - start_[g]);
  }

 private:
  std::vector<int> key_;
  std::vector<std::size_t> start_, next_;
  std::vector<Bundle> sorted_;
};

// The stretch of the volume, `width` voxels wide along b or c, where the middle lane of
// `bundle` (of `lanes`) is at slice k, or at the nearest slice it visits. In spherical views
// neighbouring views of a table look at the volume from other headings, so one column or row
// of the table is elsewhere in each; bundles of one stretch, of whichever views, share a band.
inline int stretch_of(const RayTable& t, const Bundle& bundle, std::size_t lanes, float k, bool along_c, float width) {
  const std::size_t r = bundle.r + lanes / 2;
  const float at = std::clamp(k, static_cast<float>(bundle.k_lo), static_cast<float>(bundle.k_hi));
  const float p = (along_c ? t.pc_mid[r] : t.pb_mid[r]) + (along_c ? t.beta_c[r] : t.beta_b[r]) * (at - t.k_mid[r]);
  // A middle lane far outside the volume (it may miss it) joins the nearest of a few stretches.
  return static_cast<int>(std::floor(std::clamp(p, -4096.0f, 4096.0f) / width));
}

// volume += the band, where the volume is: rows along b (contiguous), for bundles along y and z.
// sa and sc are the volume's strides along the bundles' axis and c; n_b and n_c its size.
template <class DF>
HWY_INLINE void add_band(DF df, const QuadBand& band, std::ptrdiff_t sa, std::ptrdiff_t sc, int n_b, int n_c,
                         float* HWY_RESTRICT volume) {
  const int N = static_cast<int>(hn::Lanes(df));
  const int b_lo = std::max(0, -band.b0), b_hi = std::min(band.width, n_b - band.b0);
  const int c_lo = std::max(0, -band.c0), c_hi = std::min(band.height, n_c - band.c0);
  for (int kk = 0; kk < band.slices; ++kk)
    for (int cc = c_lo; cc < c_hi; ++cc) {
      float* row = volume + (band.k0 + kk) * sa + (band.c0 + cc) * sc + band.b0;
      for (int bb = b_lo; bb < b_hi; bb += N) {
        const auto sum = band.load(df, kk, cc, bb);
        if (bb + N <= b_hi) {
          hn::StoreU(hn::Add(hn::LoadU(df, row + bb), sum), df, row + bb);
        } else {
          // The row's last, partial vector through an aligned buffer: Highway 1.0's MaskedLoad is an
          // aligned load on SSE4, and row + bb is not aligned (UBSan in the sanitizer build).
          constexpr std::size_t lanes = hn::MaxLanes(decltype(df)());
          const std::size_t count = static_cast<std::size_t>(b_hi - bb);
          HWY_ALIGN float tail[lanes] = {};
          std::copy_n(row + bb, count, tail);
          hn::Store(hn::Add(hn::Load(df, tail), sum), df, tail);
          std::copy_n(tail, count, row + bb);
        }
      }
    }
}

// A band of bundles along x (b = y, c = z, slices along x) as add_tile reads a tile: it is added
// back through the same transposition into lines along x.
struct BandAlongX {
  int k0, slices, y0, width, z0, height;
  const QuadBand* band;
  explicit BandAlongX(const QuadBand& q)
      : k0(q.k0), slices(q.slices), y0(q.b0), width(q.width), z0(q.c0), height(q.height), band(&q) {}
  template <class D>
  HWY_INLINE hn::Vec<D> load(D d, int kk, int zz, int yy) const {
    return band->load(d, kk, zz, yy);
  }
  float at(int kk, int zz, int yy) const { return band->at(kk, zz, yy); }
};

#endif  // HWY_TARGET != HWY_SCALAR
}  // namespace HWY_NAMESPACE
}  // namespace ctk::detail
HWY_AFTER_NAMESPACE();

#endif

// Per SIMD target (included by joseph_kernels.cpp in each of Highway's target passes): where the
// Joseph samples of N neighbouring rays fall at one slice, and how their four bilinear corners
// are read (gathers) and written (lane by lane). Every path computes positions and weights
// here, so forward and back agree sample by sample.
#if defined(CTK_PROJ_JOSEPH_SAMPLES_INL_H_) == defined(HWY_TARGET_TOGGLE)
#ifdef CTK_PROJ_JOSEPH_SAMPLES_INL_H_
#undef CTK_PROJ_JOSEPH_SAMPLES_INL_H_
#else
#define CTK_PROJ_JOSEPH_SAMPLES_INL_H_
#endif

#include <hwy/cache_control.h>
#include <hwy/highway.h>

#include <algorithm>
#include <cmath>
#include <cstdint>

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
  hn::Vec<DF> fb, fc;  // fractions along b and c
};

// Whole floats below 2^22 in magnitude as integers, minus an origin, in two instructions: adding
// 1.5 * 2^23 places such a float exactly in the low mantissa bits, so the sum's bits minus the
// constant's bits are the integer. A lane in its ray's range samples inside the grid (give or
// take a voxel), far below 2^22; other lanes' indices are never used (masked paths give them
// voxel 0 and weight zero). It replaces ConvertTo, whose fix-up for overflow cost four more
// instructions per vector on AVX-512, twice per sample: forward 1.04-1.08x, back 1.01-1.02x on
// the Zen 5, indices bit for bit the same (benchmarks/paired.py).
template <class DF>
class WholeToInt {
 public:
  WholeToInt(DF, int origin) : shift_(hn::Set(hn::RebindToSigned<DF>(), kMagicBits + origin)) {}
  hn::Vec<hn::RebindToSigned<DF>> operator()(DF df, hn::Vec<DF> whole) const {
    return hn::Sub(hn::BitCast(hn::RebindToSigned<DF>(), hn::Add(whole, hn::Set(df, kMagic))), shift_);
  }

 private:
  static constexpr float kMagic = 12582912.0f;  // 1.5 * 2^23
  static constexpr std::int32_t kMagicBits = 0x4B400000;
  hn::Vec<hn::RebindToSigned<DF>> shift_;  // the origin plus kMagicBits
};

// The rays of bundle r, loaded once for the samples of several slices (a loop that stores
// would otherwise reload them: vector stores may alias the table).
template <class DF>
struct BundlePosition {
  hn::Vec<DF> k_mid, beta_b, pb_mid, beta_c, pc_mid;
  WholeToInt<DF> index_b, index_c;  // indices relative to the grid's origin along b and c
  BundlePosition(DF df, const RayTable& t, std::size_t r)
      : k_mid(hn::LoadU(df, t.k_mid.data() + r)),
        beta_b(hn::LoadU(df, t.beta_b.data() + r)),
        pb_mid(hn::LoadU(df, t.pb_mid.data() + r)),
        beta_c(hn::LoadU(df, t.beta_c.data() + r)),
        pc_mid(hn::LoadU(df, t.pc_mid.data() + r)),
        index_b(df, t.origin_b),
        index_c(df, t.origin_c) {}
  // Lane l at slice k[l]; indices relative to the grid's origin (RayTable::origin_b, origin_c).
  SamplePosition<DF> at(DF df, hn::Vec<DF> k) const {
    const auto dk = hn::Sub(k, k_mid);
    const auto pb = hn::MulAdd(dk, beta_b, pb_mid);
    const auto pc = hn::MulAdd(dk, beta_c, pc_mid);
    const auto fb0 = hn::Floor(pb), fc0 = hn::Floor(pc);
    SamplePosition<DF> s;
    s.ib = index_b(df, fb0);
    s.ic = index_c(df, fc0);
    s.fb = hn::Sub(pb, fb0);
    s.fc = hn::Sub(pc, fc0);
    return s;
  }
  SamplePosition<DF> at(DF df, int k) const { return at(df, hn::Set(df, static_cast<float>(k))); }
};

template <class DF>
HWY_INLINE SamplePosition<DF> position_at(DF df, const RayTable& t, std::size_t r, hn::Vec<DF> k) {
  return BundlePosition<DF>(df, t, r).at(df, k);
}

template <class DF>
HWY_INLINE SamplePosition<DF> position_at(DF df, const RayTable& t, std::size_t r, int k) {
  return position_at(df, t, r, hn::Set(df, static_cast<float>(k)));
}

// The bilinear weights of corners (b, c), (b + 1, c), (b, c + 1), (b + 1, c + 1) from the
// fractions fb, fc: every path (masked, interior, row window, both directions) takes them from
// here.
template <class V>
HWY_INLINE void bilinear_weights(V fb, V fc, V (&weight)[4]) {
  const V one = hn::Set(hn::DFromV<V>(), 1.0f);
  const V gb = hn::Sub(one, fb), gc = hn::Sub(one, fc);
  weight[0] = hn::Mul(gb, gc);
  weight[1] = hn::Mul(fb, gc);
  weight[2] = hn::Mul(gb, fc);
  weight[3] = hn::Mul(fb, fc);
}

template <class DF>
HWY_INLINE void bilinear_weights(const SamplePosition<DF>& p, hn::Vec<DF> (&weight)[4]) {
  bilinear_weights(p.fb, p.fc, weight);
}

// What the masked paths (corners_at, pair_corners_at) know of the sample at slice k of the
// rays at entry r: where it falls, which lanes take part (in `lanes` and in their ray's range)
// and which corners are inside the volume.
template <class DF>
struct MaskedSample {
  using DI = hn::RebindToSigned<DF>;
  using VI = hn::Vec<DI>;
  SamplePosition<DF> p;
  hn::Mask<DF> active;
  hn::Mask<DF> vb0, vb1, vc0, vc1;  // corners b, b + 1, c, c + 1 inside: -1 < index < n
  VI nb, nc, sb, sc;
  VI base;  // slice k's first voxel
  MaskedSample(DF df, const RayTable& t, std::size_t r, int k, hn::Mask<DF> lanes) {
    const DI di;
    const VI vk = hn::Set(di, k);
    const VI k_first = hn::LoadU(di, t.k_first.data() + r), k_last = hn::LoadU(di, t.k_last.data() + r);
    const VI minus_one = hn::Set(di, -1), one = hn::Set(di, 1);
    // (Highway 1.0 compares signed lanes with Lt/Gt only.)
    const auto in_range = hn::And(hn::Lt(k_first, hn::Add(vk, one)), hn::Lt(vk, hn::Add(k_last, one)));
    active = hn::And(lanes, hn::RebindMask(df, in_range));
    p = position_at(df, t, r, k);
    nb = hn::LoadU(di, t.n_b.data() + r);
    nc = hn::LoadU(di, t.n_c.data() + r);
    const VI ib1 = hn::Add(p.ib, one), ic1 = hn::Add(p.ic, one);
    vb0 = hn::RebindMask(df, hn::And(hn::Gt(p.ib, minus_one), hn::Lt(p.ib, nb)));
    vb1 = hn::RebindMask(df, hn::And(hn::Gt(ib1, minus_one), hn::Lt(ib1, nb)));
    vc0 = hn::RebindMask(df, hn::And(hn::Gt(p.ic, minus_one), hn::Lt(p.ic, nc)));
    vc1 = hn::RebindMask(df, hn::And(hn::Gt(ic1, minus_one), hn::Lt(ic1, nc)));
    sb = hn::LoadU(di, t.stride_b.data() + r);
    sc = hn::LoadU(di, t.stride_c.data() + r);
    base = hn::Mul(hn::Set(di, k - t.origin_a), hn::LoadU(di, t.stride_a.data() + r));
  }
  // The bilinear weights of corners (b, c), (b + 1, c), (b, c + 1), (b + 1, c + 1), zero for
  // corners outside the volume and for lanes not active.
  void weights(hn::Vec<DF> (&w)[4]) const {
    bilinear_weights(p, w);
    w[0] = hn::IfThenElseZero(hn::And(active, hn::And(vb0, vc0)), w[0]);
    w[1] = hn::IfThenElseZero(hn::And(active, hn::And(vb1, vc0)), w[1]);
    w[2] = hn::IfThenElseZero(hn::And(active, hn::And(vb0, vc1)), w[2]);
    w[3] = hn::IfThenElseZero(hn::And(active, hn::And(vb1, vc1)), w[3]);
  }
  // The voxel at (jb, jc) of slice k for the active lanes; voxel 0 for the others (slice k may
  // lie outside the volume for a lane of another axis). Their weights are zero.
  VI index(VI jb, VI jc) const {
    return hn::IfThenElseZero(hn::RebindMask(DI(), active), hn::Add(base, hn::Add(hn::Mul(jb, sb), hn::Mul(jc, sc))));
  }
};

// A masked sample's corners and the lanes that take part (the others read voxel 0 with weight
// zero).
template <class DF>
struct MaskedCorners {
  Corners<DF> corners;
  hn::Mask<DF> active;
};

template <class DF>
HWY_INLINE MaskedCorners<DF> corners_at(DF df, const RayTable& t, std::size_t r, int k, hn::Mask<DF> lanes) {
  const hn::RebindToSigned<DF> di;
  const MaskedSample<DF> s(df, t, r, k, lanes);
  const auto zero = hn::Zero(di), one = hn::Set(di, 1);
  const auto nb1 = hn::Sub(s.nb, one), nc1 = hn::Sub(s.nc, one);
  const auto jb0 = hn::Min(hn::Max(s.p.ib, zero), nb1), jb1 = hn::Min(hn::Max(hn::Add(s.p.ib, one), zero), nb1);
  const auto jc0 = hn::Min(hn::Max(s.p.ic, zero), nc1), jc1 = hn::Min(hn::Max(hn::Add(s.p.ic, one), zero), nc1);
  MaskedCorners<DF> out;
  out.active = s.active;
  Corners<DF>& c = out.corners;
  c.index[0] = s.index(jb0, jc0);
  c.index[1] = s.index(jb1, jc0);
  c.index[2] = s.index(jb0, jc1);
  c.index[3] = s.index(jb1, jc1);
  s.weights(c.weight);
  return out;
}

// Weights of a pair of floats at j = clamp(i, 0, n - 2) along one axis, from the corners'
// weights w0 (corner i) and w1 (corner i + 1), each already zero where outside.
template <class DF>
HWY_INLINE void pair_weights(DF df, hn::Vec<hn::RebindToSigned<DF>> i, hn::Vec<hn::RebindToSigned<DF>> n2, hn::Vec<DF> w0,
                             hn::Vec<DF> w1, hn::Vec<DF>& first, hn::Vec<DF>& second) {
  const auto low = hn::RebindMask(df, hn::Lt(i, hn::Zero(hn::RebindToSigned<DF>())));  // corner i + 1 at j
  const auto high = hn::RebindMask(df, hn::Gt(i, n2));                                 // corner i at j + 1
  first = hn::IfThenElse(low, w1, hn::IfThenZeroElse(high, w0));
  second = hn::IfThenZeroElse(low, hn::IfThenElse(high, w0, w1));
}

// The sample of corners_at as two pairs of neighbouring floats, for bundles whose b is the
// contiguous axis (Bundle::pairs): `corners` as an interior sample has them (index[0] the pair in
// row c, index[2] the pair in row c + 1; corners 1 and 3 one voxel on), with each pair's first
// voxel clamped so that both pairs are inside the volume. A corner outside the volume then has
// no place in the pairs, or its neighbour inside takes its place: at b = -1 the pair starts at
// 0 and its first float weighs corner b + 1; at b = n - 1 it starts at n - 2 and its second
// float weighs corner b. Along c the same. The weights are corners_at's, bit for bit, moved;
// lanes outside `active` read voxel 0 with weight zero. Half the gathers of corners_at's four
// on the volume's rim, and half the additions back.
template <class DF>
HWY_INLINE MaskedCorners<DF> pair_corners_at(DF df, const RayTable& t, std::size_t r, int k, hn::Mask<DF> lanes) {
  const hn::RebindToSigned<DF> di;
  const MaskedSample<DF> s(df, t, r, k, lanes);
  const auto zero = hn::Zero(di), two = hn::Set(di, 2);
  const auto nb2 = hn::Sub(s.nb, two), nc2 = hn::Sub(s.nc, two);
  const auto jb = hn::Min(hn::Max(s.p.ib, zero), nb2), jc = hn::Min(hn::Max(s.p.ic, zero), nc2);
  const auto one = hn::Set(df, 1.0f);
  hn::Vec<DF> b0, b1, c0, c1;
  pair_weights(df, s.p.ib, nb2, hn::IfThenElseZero(s.vb0, hn::Sub(one, s.p.fb)), hn::IfThenElseZero(s.vb1, s.p.fb), b0, b1);
  pair_weights(df, s.p.ic, nc2, hn::IfThenElseZero(s.vc0, hn::Sub(one, s.p.fc)), hn::IfThenElseZero(s.vc1, s.p.fc), c0, c1);
  MaskedCorners<DF> out;
  out.active = s.active;
  Corners<DF>& c = out.corners;
  c.index[0] = s.index(jb, jc);
  c.index[1] = hn::Add(c.index[0], hn::Set(di, 1));
  c.index[2] = hn::Add(c.index[0], s.sc);
  c.index[3] = hn::Add(c.index[2], hn::Set(di, 1));
  // As bilinear_weights multiplies them.
  c.weight[0] = hn::IfThenElseZero(s.active, hn::Mul(b0, c0));
  c.weight[1] = hn::IfThenElseZero(s.active, hn::Mul(b1, c0));
  c.weight[2] = hn::IfThenElseZero(s.active, hn::Mul(b0, c1));
  c.weight[3] = hn::IfThenElseZero(s.active, hn::Mul(b1, c1));
  return out;
}

// Same sample as corners_at for lanes known to be well inside the volume (all four corners
// valid) and inside their ray's range: identical arithmetic, no masks. The bundle's rays and
// strides are read once, for loops over slices (as BundlePosition).
template <class DF>
struct InteriorBundle {
  using VI = hn::Vec<hn::RebindToSigned<DF>>;
  BundlePosition<DF> position;
  VI sa, sb, sc;
  int origin_a;
  InteriorBundle(DF df, const RayTable& t, std::size_t r)
      : position(df, t, r),
        sa(hn::LoadU(hn::RebindToSigned<DF>(), t.stride_a.data() + r)),
        sb(hn::LoadU(hn::RebindToSigned<DF>(), t.stride_b.data() + r)),
        sc(hn::LoadU(hn::RebindToSigned<DF>(), t.stride_c.data() + r)),
        origin_a(t.origin_a) {}
  Corners<DF> at(DF df, int k) const {
    const hn::RebindToSigned<DF> di;
    const VI vk = hn::Set(di, k - origin_a);
    const SamplePosition<DF> p = position.at(df, k);
    const VI i00 = hn::Add(hn::Mul(vk, sa), hn::Add(hn::Mul(p.ib, sb), hn::Mul(p.ic, sc)));
    Corners<DF> out;
    out.index[0] = i00;
    out.index[1] = hn::Add(i00, sb);
    out.index[2] = hn::Add(i00, sc);
    out.index[3] = hn::Add(out.index[1], sc);
    bilinear_weights(p, out.weight);
    return out;
  }
};

template <class DF>
HWY_INLINE Corners<DF> interior_corners_at(DF df, const RayTable& t, std::size_t r, int k) {
  return InteriorBundle<DF>(df, t, r).at(df, k);
}

// Slices where every lane of the bundle (those with `axis`, or all when axis < 0) is inside its
// ray's range with all four corners at least 1e-3 voxel inside the volume (RayTable::in_first,
// in_last): the fast path. Empty (lo > hi) when any such lane has none.
HWY_INLINE void interior_range(const RayTable& t, std::size_t r, std::size_t n, int axis, int& lo, int& hi) {
  lo = -(1 << 30);
  hi = 1 << 30;
  for (std::size_t l = 0; l < n; ++l) {
    const std::size_t i = r + l;
    if (axis >= 0 && t.axis[i] != axis) continue;
    if (t.in_last[i] < t.in_first[i]) {
      lo = 1 << 30;
      return;
    }
    lo = std::max(lo, t.in_first[i]);
    hi = std::min(hi, t.in_last[i]);
  }
}

// At slice k: `inside` = the lanes whose four corners are all inside the volume there
// (RayTable::in_first, in_last). False when some other lane is in its ray's range there (on the
// volume's rim, where only the masked path places it).
template <class DI>
HWY_INLINE bool interior_lanes(DI di, const RayTable& t, std::size_t r, int k, hn::Mask<DI>& inside) {
  const auto vk = hn::Set(di, k), one = hn::Set(di, 1);
  const auto between = [&](const std::int32_t* first, const std::int32_t* last) {
    return hn::And(hn::Lt(hn::LoadU(di, first + r), hn::Add(vk, one)), hn::Lt(vk, hn::Add(hn::LoadU(di, last + r), one)));
  };
  inside = between(t.in_first.data(), t.in_last.data());
  return hn::AllFalse(di, hn::AndNot(inside, between(t.k_first.data(), t.k_last.data())));
}

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
    b.pairs = b.pairs && t.stride_b[i] == 1 && t.n_b[i] >= 2 && t.n_c[i] >= 2;  // two pairs fit (pair_corners_at)
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
  b.axis = t.axis[r];
  for (std::size_t l = 1; l < n; ++l)
    if (t.axis[r + l] != b.axis) b.axis = -2;
  return b;
}

// bundle_at, from the bundles the table's fillers prepared (all lanes, RayTable::bundles) where
// they are the same: for every lane (axis < 0), or where every lane is on `axis`.
HWY_INLINE Bundle table_bundle(const RayTable& t, std::size_t r, std::size_t n, int axis) {
  const std::size_t i = r / n;
  if (i < t.bundles.size() && (axis < 0 || t.bundles[i].axis == axis)) return t.bundles[i];
  return bundle_at(t, r, n, axis);
}

// The two floats at volume[index] and volume[index + 1] for every lane, as (first, second): one
// 64-bit gather per pair instead of two 32-bit ones (gathers cost per element loaded).
template <class DF>
HWY_INLINE void gather_pairs(DF df, const float* HWY_RESTRICT volume, hn::Vec<hn::RebindToSigned<DF>> index, hn::Vec<DF>& first,
                             hn::Vec<DF>& second) {
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

// v[0] += w[0] and v[1] += w[1]: a pair of floats, with one load, add and store where the
// target has 64-bit vectors.
HWY_INLINE void add_pair(float* HWY_RESTRICT v, const float* HWY_RESTRICT w) {
#if HWY_TARGET == HWY_SCALAR
  v[0] += w[0];
  v[1] += w[1];
#elif HWY_ARCH_X86 && HWY_TARGET <= HWY_AVX2
  // With VEX encoding, w's load folds into the add as four floats: one instruction fewer per pair
  // (w[2] and w[3] are read, never used; the weight buffers carry a spare slice for the last
  // lane's).
  _mm_storel_pi(reinterpret_cast<__m64*>(v),
                _mm_add_ps(_mm_castsi128_ps(_mm_loadl_epi64(reinterpret_cast<const __m128i*>(v))), _mm_loadu_ps(w)));
#else
  const hn::CappedTag<float, 2> d2;
  hn::StoreU(hn::Add(hn::LoadU(d2, v), hn::LoadU(d2, w)), d2, v);
#endif
}

// a[0], b[0], a[1], b[1], ... at `out` (aligned), as StoreInterleaved2 stores them: the weights of
// corners b and b + 1 side by side for the scatters' pairs. On AVX-512 two permutes across the
// whole vector, where Highway 1.0 takes six shuffles (unpacks within 128-bit blocks, then the
// blocks reordered): back projection 1.01-1.03x on the Zen 5 (benchmarks/paired.py).
template <class DF>
HWY_INLINE void store_interleaved(DF df, hn::Vec<DF> a, hn::Vec<DF> b, float* HWY_RESTRICT out) {
#if HWY_TARGET <= HWY_AVX3
  static_assert(hn::MaxLanes(DF()) == 16, "the kernels take whole AVX-512 vectors");
  (void)df;
  const __m512i lower = _mm512_setr_epi32(0, 16, 1, 17, 2, 18, 3, 19, 4, 20, 5, 21, 6, 22, 7, 23);
  const __m512i upper = _mm512_setr_epi32(8, 24, 9, 25, 10, 26, 11, 27, 12, 28, 13, 29, 14, 30, 15, 31);
  _mm512_store_ps(out, _mm512_permutex2var_ps(a.raw, lower, b.raw));
  _mm512_store_ps(out + 16, _mm512_permutex2var_ps(a.raw, upper, b.raw));
#else
  hn::StoreInterleaved2(a, b, df, out);
#endif
}

// Whether a kernel asks for its rows ahead (prefetch_span, below): in the volume, yes; in a tile,
// which was just filled, no.
enum class Rows { fetch_ahead, cached };

// Asks for the cache lines of first[0 .. kFloats - 1] ahead of the loads. The kernels' first
// pass finds every slice's voxels a whole pass before the second loads them. In spherical views
// those voxels are mostly outside L2 (each view reads the whole volume, and the next view shares
// little of it), and without asking, the second pass met the misses about one slice at a time
// (spherical views 1.05-1.2x faster each way on the Zen 3, circular ones unchanged;
// benchmarks/README.md, benchmarks/paired.py). Not for tiles: they were just filled. The width is a
// constant so that this is straight-line code: as a loop over a run-time width it took 5-13 % of
// a view's forward instructions on AVX2 (benchmarks/paired.py).
template <int kFloats>
HWY_INLINE void prefetch_span(const float* first) {
  for (int i = 0; i < kFloats - 1; i += 16) hwy::Prefetch(first + i);  // 16 floats: a 64-byte line
  hwy::Prefetch(first + kFloats - 1);
}

// The same for the line of voxel v and of the voxel a row (dc) above it.
HWY_INLINE void prefetch_corner_rows(const float* v, std::ptrdiff_t dc) {
  hwy::Prefetch(v);
  hwy::Prefetch(v + dc);
}

// The lines of the pairs at row0[l] and row1[l] (voxel indices) of every 8th lane and the last:
// 8 lanes' pairs span a line or two.
HWY_INLINE void prefetch_pair_rows(const float* volume, const std::int32_t* row0, const std::int32_t* row1, int lanes) {
  for (int l = 0; l < lanes; l += 8) {
    hwy::Prefetch(volume + row0[l]);
    hwy::Prefetch(volume + row1[l]);
  }
  hwy::Prefetch(volume + row0[lanes - 1] + 1);
  hwy::Prefetch(volume + row1[lanes - 1] + 1);
}

// Slices per pass of the rim paths (scatter_add_rim_slices below, add_rim_samples).
inline constexpr int kRimBatch = 16;

// The lanes of a mask as bits (lane l at bit l): the first two bytes StoreMaskBits writes.
template <class DF>
HWY_INLINE std::uint32_t lane_bits(DF df, hn::Mask<DF> m) {
  static_assert(kMaxLanes <= 16, "lane_bits reads two bytes of mask bits");
  std::uint8_t bytes[8] = {};
  hn::StoreMaskBits(df, m, bytes);
  return static_cast<std::uint32_t>(bytes[0]) | static_cast<std::uint32_t>(bytes[1]) << 8;
}

// The back projection's masked slices [k_lo, k_hi] of bundle b (on the volume's rim, or with
// lanes of other axes) for the lanes in `lanes`: volume[index] += weight * value over each
// sample's corners, lane by lane (lanes often share a voxel). Pairs bundles add
// pair_corners_at's two pairs, the others corners_at's four corners. Corners outside the volume
// weigh zero at a voxel of the same slice, so no corner is tested; lanes outside a slice's
// active ones touch nothing there (their voxel 0 may be in another thread's slab). Two passes,
// as scatter_add_interior_slices (and for the same reasons): every slice's corners first, their
// lines asked for with Rows::fetch_ahead, then the additions. Slice by slice, testing each
// corner's weight, the additions waited for their lines: 15 % of BackRays' time in spherical
// views on the Zen 4 (benchmarks/paired.py). (A gather, add and scatter per corner was tried: 1.7x slower
// on Zen 5, the next corner's gather waiting for the scatter's stores.)
template <class DF>
HWY_INLINE void scatter_add_rim_slices(DF df, const RayTable& t, const Bundle& b, int k_lo, int k_hi, hn::Mask<DF> lanes,
                                       hn::Vec<DF> value, float* HWY_RESTRICT volume, Rows fetch) {
  const hn::RebindToSigned<DF> di;
  const int N = static_cast<int>(hn::Lanes(df));
  HWY_ALIGN std::int32_t index[kRimBatch][4][kMaxLanes];  // pairs: index[i][0] and [i][2] only
  HWY_ALIGN float weight[kRimBatch + 1][4][kMaxLanes];    // pairs: weight[i][q][2l + (0, 1)], q = 0, 2; + 1: add_pair
  std::uint32_t active[kRimBatch];
  for (int k0 = k_lo; k0 <= k_hi; k0 += kRimBatch) {
    const int count = std::min(kRimBatch, k_hi - k0 + 1);
    for (int i = 0; i < count; ++i) {
      const MaskedCorners<DF> m = b.pairs ? pair_corners_at(df, t, b.r, k0 + i, lanes) : corners_at(df, t, b.r, k0 + i, lanes);
      const Corners<DF>& c = m.corners;
      active[i] = lane_bits(df, m.active);
      const auto weighed = [&](int q) { return hn::Mul(c.weight[q], value); };
      if (b.pairs) {
        for (int q = 0; q < 4; q += 2) {
          hn::Store(c.index[q], di, index[i][q]);
          store_interleaved(df, weighed(q), weighed(q + 1), weight[i][q]);
        }
        if (fetch == Rows::fetch_ahead) prefetch_pair_rows(volume, index[i][0], index[i][2], N);
        continue;
      }
      for (int q = 0; q < 4; ++q) {
        hn::Store(c.index[q], di, index[i][q]);
        hn::Store(weighed(q), df, weight[i][q]);
        if (fetch == Rows::fetch_ahead)  // the lanes' corners lie in rows or planes of their own
          for (int l = 0; l < N; ++l) hwy::Prefetch(volume + index[i][q][l]);
      }
    }
    for (int l = 0; l < N; ++l)
      for (int i = 0; i < count; ++i) {
        if (!(active[i] >> l & 1u)) continue;
        if (b.pairs) {
          add_pair(volume + index[i][0][l], weight[i][0] + 2 * l);
          add_pair(volume + index[i][2][l], weight[i][2] + 2 * l);
        } else {
          for (int q = 0; q < 4; ++q) volume[index[i][q][l]] += weight[i][q][l];
        }
      }
  }
}

#if HWY_TARGET == HWY_AVX2
// position_at for one bundle of 8 lanes on AVX2, its rays loaded once: the same arithmetic in
// the instructions it needs. Highway's ConvertTo fixes up float-to-int overflow (about five
// instructions per vector), which indices inside the grid never need; on the AVX2 kernels'
// interior paths that was a tenth of a sample's instructions, on its chain to the loads.
struct BundlePositionAvx2 {
  __m256 k_mid, beta_b, pb_mid, beta_c, pc_mid;
  __m256i origin_b, origin_c;
  BundlePositionAvx2(const RayTable& t, std::size_t r)
      : k_mid(_mm256_loadu_ps(t.k_mid.data() + r)),
        beta_b(_mm256_loadu_ps(t.beta_b.data() + r)),
        pb_mid(_mm256_loadu_ps(t.pb_mid.data() + r)),
        beta_c(_mm256_loadu_ps(t.beta_c.data() + r)),
        pc_mid(_mm256_loadu_ps(t.pc_mid.data() + r)),
        origin_b(_mm256_set1_epi32(t.origin_b)),
        origin_c(_mm256_set1_epi32(t.origin_c)) {}
  // Lower corner (ib, ic) relative to the grid's origin and the fractions (fb, fc) at slice k.
  HWY_INLINE void at(int k, __m256i& ib, __m256i& ic, __m256& fb, __m256& fc) const {
    at(_mm256_set1_ps(static_cast<float>(k)), ib, ic, fb, fc);
  }
  // The same with k given as a float in every lane.
  HWY_INLINE void at(__m256 k, __m256i& ib, __m256i& ic, __m256& fb, __m256& fc) const {
    const __m256 dk = _mm256_sub_ps(k, k_mid);
    const __m256 pb = _mm256_fmadd_ps(dk, beta_b, pb_mid), pc = _mm256_fmadd_ps(dk, beta_c, pc_mid);
    const __m256 fb0 = _mm256_floor_ps(pb), fc0 = _mm256_floor_ps(pc);
    ib = _mm256_sub_epi32(_mm256_cvttps_epi32(fb0), origin_b);
    ic = _mm256_sub_epi32(_mm256_cvttps_epi32(fc0), origin_c);
    fb = _mm256_sub_ps(pb, fb0);
    fc = _mm256_sub_ps(pc, fc0);
  }
};

// interior_corners_at for `count` slices from k0, corner 0's index and the weights times
// `value` stored for the scatter (in pairs as scatter_add_interior_slices says). Every lane of
// an interior bundle shares the axis and its strides.
HWY_INLINE void interior_corners_avx2(const RayTable& t, std::size_t r, int k0, int count, __m256 value, bool pairs,
                                      std::int32_t (*index)[kMaxLanes], float (*weight)[4][kMaxLanes]) {
  const BundlePositionAvx2 position(t, r);
  const __m256i sb = _mm256_set1_epi32(t.stride_b[r]), sc = _mm256_set1_epi32(t.stride_c[r]);
  const int origin_a = t.origin_a, sa = t.stride_a[r];  // read once: the stores below may alias t
  const __m256 one = _mm256_set1_ps(1.0f);
  __m256 kf = _mm256_set1_ps(static_cast<float>(k0));
  for (int i = 0; i < count; ++i, kf = _mm256_add_ps(kf, one)) {
    __m256i ib, ic;
    __m256 fb, fc;
    position.at(kf, ib, ic, fb, fc);
    const __m256i base = _mm256_set1_epi32((k0 + i - origin_a) * sa);
    const __m256i i00 = _mm256_add_epi32(base, _mm256_add_epi32(_mm256_mullo_epi32(ib, sb), _mm256_mullo_epi32(ic, sc)));
    _mm256_store_si256(reinterpret_cast<__m256i*>(index[i]), i00);
    const __m256 gb = _mm256_sub_ps(one, fb), gc = _mm256_sub_ps(one, fc);
    const __m256 w[4] = {_mm256_mul_ps(_mm256_mul_ps(gb, gc), value), _mm256_mul_ps(_mm256_mul_ps(fb, gc), value),
                         _mm256_mul_ps(_mm256_mul_ps(gb, fc), value), _mm256_mul_ps(_mm256_mul_ps(fb, fc), value)};
    if (!pairs) {
      for (int q = 0; q < 4; ++q) _mm256_store_ps(weight[i][q], w[q]);
      continue;
    }
    for (int q = 0; q < 4; q += 2) {  // lanes 0, 1, 4, 5 and 2, 3, 6, 7 interleaved, then in order
      const __m256 lo = _mm256_unpacklo_ps(w[q], w[q + 1]), hi = _mm256_unpackhi_ps(w[q], w[q + 1]);
      _mm256_store_ps(weight[i][q], _mm256_permute2f128_ps(lo, hi, 0x20));
      _mm256_store_ps(weight[i][q] + 8, _mm256_permute2f128_ps(lo, hi, 0x31));
    }
  }
}
#endif

// The interior slices [k_lo, k_hi] of bundle r, in order, scattered lane by lane like
// scatter_add_rim_slices (above) but where every lane is on the slab's axis and every corner
// inside the volume: no masks, and corners 1 to 3 are offsets of corner 0. Two passes over up to
// kInteriorBatch slices: every slice's corners first, then the scatters (as the forward
// projection's add_window_samples; 6-14 % faster on the Zen 3, benchmarks/paired.py). The scatters go lane
// by lane, each lane through every slice: neighbouring lanes share voxels, and a lane's stores
// to them are then slices of work ahead of the next lane's loads instead of just before them
// (1.05-1.06x, benchmarks/paired.py); on AVX-512 pairs go slice by slice, even lanes before odd ones
// (below). Where b is the contiguous axis (all but rays along x outside tiles), corners b and
// b + 1 are added as one pair of floats, their weights stored interleaved: half the loads and
// stores (1.04-1.13x, benchmarks/paired.py). A voxel receives each lane by its own float addition, as on
// the masked path (in lane order, except AVX-512's pairs: an odd lane after the even lane
// above it). With Rows::fetch_ahead, the pairs' lines are asked for between the passes
// (prefetch_span, above).
inline constexpr int kInteriorBatch = 16;
// One batch of those slices of one bundle: corners() is the first pass (and asks for the rows),
// add() the second. Apart so that BackRays can find the next bundle's corners, and ask for its
// rows, before adding this one's.
template <class DF>
struct InteriorScatter {
  HWY_ALIGN std::int32_t index[kInteriorBatch][kMaxLanes];
  HWY_ALIGN float weight[kInteriorBatch + 1][4][kMaxLanes];  // [i][q][l], or paired [i][q][2l + (0, 1)]; + 1: add_pair
  int count = 0;                                             // slices found
  std::int32_t db = 0, dc = 0;                               // corner offsets, as in interior_corners_at
  bool pairs = false;

  // Slices [k0, k0 + slices) of bundle r (slices <= kInteriorBatch), `value` already times the
  // path length.
  HWY_INLINE void corners(DF df, const RayTable& t, std::size_t r, int k0, int slices, hn::Vec<DF> value, const float* volume,
                          Rows fetch) {
    const int N = static_cast<int>(hn::Lanes(df));
    count = slices;
    db = t.stride_b[r];
    dc = t.stride_c[r];
    pairs = HWY_TARGET != HWY_SCALAR && db == 1;
#if HWY_TARGET == HWY_AVX2
    interior_corners_avx2(t, r, k0, count, value.raw, pairs, index, weight);
#else
    const InteriorBundle<DF> bundle(df, t, r);
    for (int i = 0; i < count; ++i) {
      const Corners<DF> c = bundle.at(df, k0 + i);
      hn::Store(c.index[0], hn::RebindToSigned<DF>(), index[i]);
      hn::Vec<DF> w[4];
      for (int q = 0; q < 4; ++q) w[q] = hn::Mul(c.weight[q], value);
      if (!pairs)
        for (int q = 0; q < 4; ++q) hn::Store(w[q], df, weight[i][q]);
      else
        for (int q = 0; q < 4; q += 2) store_interleaved(df, w[q], w[q + 1], weight[i][q]);
    }
#endif
    if (pairs && fetch == Rows::fetch_ahead)  // both rows under every 8th lane's pair and the last's (8 lanes span a line or two)
      for (int i = 0; i < count; ++i) {
        for (int l = 0; l < N; l += 8) prefetch_corner_rows(volume + index[i][l], dc);
        prefetch_corner_rows(volume + index[i][N - 1] + 1, dc);
      }
  }

  HWY_INLINE void add(DF df, float* HWY_RESTRICT volume) const {
    const int N = static_cast<int>(hn::Lanes(df));
    if (pairs) {
      const auto add_lane = [&](int i, int l) {  // lane l's pairs of slice i
        float* v = volume + index[i][l];
        add_pair(v, weight[i][0] + 2 * l);
        add_pair(v + dc, weight[i][2] + 2 * l);
      };
#if HWY_TARGET <= HWY_AVX3
      // Slice by slice, lanes 0, 2, .., 14 of slice i and then 1, 3, .., 15 of slice i - 1:
      // lanes that share a voxel (2m + 1 with 2m and 2m + 2 of its slice) are 15 or 16 lanes'
      // work apart, and each run of 8 lanes is unrolled. Slice by slice with even lanes first
      // measured 1.01-1.04x over lane by lane on the Zen 5 (0.95-0.98x on its AVX2 target, which
      // keeps lane by lane); a slice's odd lanes after the next slice's even ones 1.03-1.05x more.
      for (int i = 0; i <= count; ++i) {
        if (i < count)
          for (int m = 0; m < N / 2; ++m) add_lane(i, 2 * m);
        if (i > 0)
          for (int m = 0; m < N / 2; ++m) add_lane(i - 1, 2 * m + 1);
      }
#else
      for (int l = 0; l < N; ++l)
        for (int i = 0; i < count; ++i) add_lane(i, l);
#endif
      return;
    }
    for (int l = 0; l < N; ++l)
      for (int i = 0; i < count; ++i) {
        float* v = volume + index[i][l];
        v[0] += weight[i][0][l];
        v[db] += weight[i][1][l];
        v[dc] += weight[i][2][l];
        v[db + dc] += weight[i][3][l];
      }
  }
};

template <class DF>
HWY_INLINE void scatter_add_interior_slices(DF df, const RayTable& t, std::size_t r, int k_lo, int k_hi, hn::Vec<DF> value,
                                            float* HWY_RESTRICT volume, Rows fetch) {
  InteriorScatter<DF> batch;
  for (int k0 = k_lo; k0 <= k_hi; k0 += kInteriorBatch) {
    batch.corners(df, t, r, k0, std::min(kInteriorBatch, k_hi - k0 + 1), value, volume, fetch);
    batch.add(df, volume);
  }
}

}  // namespace HWY_NAMESPACE
}  // namespace ctk::detail
HWY_AFTER_NAMESPACE();

#endif

// Per SIMD target: preparing the rays of a run of table entries, SIMD across rays in double
// precision, and storing them in the table. The same arithmetic as march_ray (which the reference
// projector marches with), operation for operation, so the table holds the same numbers; compiled
// without contraction into FMAs (CMakeLists.txt), which would round differently. Then the interior
// range, where the kernels' mask-free paths may run.
#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "ray_table_fill.cpp"
#include <hwy/foreach_target.h>  // IWYU pragma: keep
#include <hwy/highway.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#include "ray_table.hpp"

HWY_BEFORE_NAMESPACE();
namespace ctk::detail {
namespace HWY_NAMESPACE {
namespace hn = hwy::HWY_NAMESPACE;

// The lane's value of x, y or z by its axis (0, 1, 2).
template <class V, class M>
HWY_INLINE V by_axis(M is0, M is1, V x, V y, V z) {
  return hn::IfThenElse(is0, x, hn::IfThenElse(is1, y, z));
}

// The k range where lo < p_mid + (k - k_mid) beta < hi. kWidened: clip() of ray_geometry.cpp,
// widened by one slice (the slices a ray may touch); otherwise lo <= ... <= hi, narrowed to whole
// slices (the interior range, where every corner of the sample is inside).
template <bool kWidened, class D, class V = hn::Vec<D>>
HWY_INLINE void k_range(D d, V p_mid, V beta, V lo, V hi, V k_mid, V& k_lo, V& k_hi) {
  const auto still = hn::Eq(beta, hn::Zero(d));
  const auto inside = kWidened ? hn::And(hn::Gt(p_mid, lo), hn::Lt(p_mid, hi)) : hn::And(hn::Ge(p_mid, lo), hn::Le(p_mid, hi));
  const V a = hn::Add(k_mid, hn::Div(hn::Sub(lo, p_mid), beta));
  const V b = hn::Add(k_mid, hn::Div(hn::Sub(hi, p_mid), beta));
  const V first = kWidened ? hn::Floor(hn::Min(a, b)) : hn::Ceil(hn::Min(a, b));
  const V second = kWidened ? hn::Ceil(hn::Max(a, b)) : hn::Floor(hn::Max(a, b));
  const V none = hn::Set(d, std::numeric_limits<double>::infinity());
  k_lo = hn::IfThenElse(still, hn::IfThenElse(inside, k_lo, none), hn::Max(k_lo, first));
  k_hi = hn::IfThenElse(still, k_hi, hn::Min(k_hi, second));
}

template <class D, class V = hn::Vec<D>>
HWY_INLINE V through_float(D d, V x) {
  const hn::Rebind<float, D> df;
  return hn::PromoteTo(d, hn::DemoteTo(df, x));
}

void PrepareRays(const ViewRays& rays, const VolumeLayout& layout, int grid_origin_b, int grid_origin_c, const double* u,
                 const double* v, int count, PreparedRays& out) {
  const hn::ScalableTag<double> d;
  using V = hn::Vec<decltype(d)>;
  const int N = static_cast<int>(hn::Lanes(d));
  const V n0 = hn::Set(d, layout.size[0]), n1 = hn::Set(d, layout.size[1]), n2 = hn::Set(d, layout.size[2]);
  const V one = hn::Set(d, 1.0), minus_one = hn::Set(d, -1.0), half = hn::Set(d, 0.5);
  const V origin_b = hn::Set(d, grid_origin_b), origin_c = hn::Set(d, grid_origin_c);
  for (int i = 0; i < count; i += N) {
    const V U = hn::LoadU(d, u + i), W = hn::LoadU(d, v + i);
    V dir[3];
    for (int k = 0; k < 3; ++k)
      dir[k] = hn::Add(hn::Add(hn::Set(d, rays.d0[k]), hn::Mul(U, hn::Set(d, rays.du[k]))), hn::Mul(W, hn::Set(d, rays.dv[k])));
    const V ax = hn::Abs(dir[0]), ay = hn::Abs(dir[1]), az = hn::Abs(dir[2]);
    // The first largest, as Eigen's maxCoeff finds it.
    const auto is0 = hn::And(hn::Ge(ax, ay), hn::Ge(ax, az));
    const auto is1 = hn::AndNot(is0, hn::Ge(ay, az));
    const auto is2 = hn::Not(hn::Or(is0, is1));
    const V sx = hn::Set(d, rays.source[0]), sy = hn::Set(d, rays.source[1]), sz = hn::Set(d, rays.source[2]);
    // Axes b < c besides a: (1, 2), (0, 2), (0, 1).
    const V da = by_axis(is0, is1, dir[0], dir[1], dir[2]);
    const V db = hn::IfThenElse(is0, dir[1], dir[0]), dc = hn::IfThenElse(is2, dir[1], dir[2]);
    const V sa = by_axis(is0, is1, sx, sy, sz);
    const V sb = hn::IfThenElse(is0, sy, sx), sc = hn::IfThenElse(is2, sy, sz);
    const V na = by_axis(is0, is1, n0, n1, n2);
    const V nb = hn::IfThenElse(is0, n1, n0), nc = hn::IfThenElse(is2, n1, n2);
    const V k_mid = hn::Mul(half, hn::Sub(na, one));
    const V beta_b = hn::Div(db, da), beta_c = hn::Div(dc, da);
    const V pb_mid = hn::Add(sb, hn::Mul(hn::Sub(k_mid, sa), beta_b));
    const V pc_mid = hn::Add(sc, hn::Mul(hn::Sub(k_mid, sa), beta_c));
    V sum = hn::Zero(d);
    for (int k = 0; k < 3; ++k) {
      const V scaled = hn::Mul(dir[k], hn::Set(d, layout.voxel_mm[k]));
      sum = hn::Add(sum, hn::Mul(scaled, scaled));
    }
    const V weight = hn::Div(hn::Sqrt(sum), hn::Abs(da));

    V k_lo = hn::Zero(d), k_hi = hn::Sub(na, one);
    k_range<true>(d, pb_mid, beta_b, minus_one, nb, k_mid, k_lo, k_hi);
    k_range<true>(d, pc_mid, beta_c, minus_one, nc, k_mid, k_lo, k_hi);
    // Only points in front of the source.
    const auto forward = hn::Gt(da, hn::Zero(d));
    k_lo = hn::IfThenElse(forward, hn::Max(k_lo, hn::Add(hn::Floor(sa), one)), k_lo);
    k_hi = hn::IfThenElse(forward, k_hi, hn::Min(k_hi, hn::Sub(hn::Ceil(sa), one)));
    const auto met = hn::Le(k_lo, k_hi);
    const V k_first = hn::IfThenElseZero(met, k_lo), k_last = hn::IfThenElse(met, k_hi, minus_one);

    // The interior range, from the values as stored (float).
    const V k_mid_f = through_float(d, k_mid);
    V in_lo = k_first, in_hi = k_last;
    const V margin = hn::Set(d, 1e-3);
    k_range<false>(d, hn::Sub(through_float(d, pb_mid), origin_b), through_float(d, beta_b), margin,
                   hn::Sub(hn::Sub(nb, one), margin), k_mid_f, in_lo, in_hi);
    k_range<false>(d, hn::Sub(through_float(d, pc_mid), origin_c), through_float(d, beta_c), margin,
                   hn::Sub(hn::Sub(nc, one), margin), k_mid_f, in_lo, in_hi);
    const V big = hn::Set(d, 1e9);
    in_lo = hn::Min(hn::Max(in_lo, hn::Neg(big)), big);
    in_hi = hn::Min(hn::Max(in_hi, hn::Neg(big)), big);

    const V axis = hn::IfThenElse(is0, hn::Zero(d), hn::IfThenElse(is1, one, hn::Set(d, 2.0)));
    hn::StoreU(axis, d, out.axis + i);
    hn::StoreU(beta_b, d, out.beta_b + i);
    hn::StoreU(beta_c, d, out.beta_c + i);
    hn::StoreU(pb_mid, d, out.pb_mid + i);
    hn::StoreU(pc_mid, d, out.pc_mid + i);
    hn::StoreU(weight, d, out.weight_mm + i);
    hn::StoreU(k_first, d, out.k_first + i);
    hn::StoreU(k_last, d, out.k_last + i);
    hn::StoreU(in_lo, d, out.in_first + i);
    hn::StoreU(in_hi, d, out.in_last + i);
  }
}

// LanePath::pixel of lanes lane + min(l, count - 1), l < kMaxLanes, in doubles, with the same
// operations (so the same values), stored as PrepareRays loads them. Found one lane at a time in
// RayTable::fill, the compiler's pairs of scalar results were reloaded as vectors before their
// stores had left, and that stall was most of the fill (3 % of a circular back projection in
// perf); a vector store that the same vector load reads back is forwarded.
void LanePixels(const LanePath& path, int line, int lane, int count, double* u, double* v) {
  const hn::ScalableTag<double> d;
  const hn::Rebind<std::int32_t, decltype(d)> di;
  const int N = static_cast<int>(hn::Lanes(d));
  const auto line0 = hn::Set(d, path.line_first + line), slope = hn::Set(d, path.slope), half = hn::Set(d, 0.5);
  const auto last = hn::Set(di, count - 1), first = hn::Set(di, path.major_first + lane);
  for (int i = 0; i < kMaxLanes; i += N) {
    const auto major = hn::PromoteTo(d, hn::Add(first, hn::Min(hn::Iota(di, i), last)));
    const auto minor = hn::Add(line0, hn::Floor(hn::Add(hn::Mul(major, slope), half)));
    hn::StoreU(path.along_u ? major : minor, d, u + i);
    hn::StoreU(path.along_u ? minor : major, d, v + i);
  }
}

// Entries [first, first + count) of t from p, SIMD across rays: floats rounded from the doubles
// as static_cast rounds them, the integers exact, each axis's strides and sizes picked per lane.
// (One entry at a time, with its axis looked up, this took most of RayTable::fill: 4 % of a
// spherical back projection on the Zen 4, benchmarks/paired.py.)
void StoreRays(const PreparedRays& p, const VolumeLayout& layout, int count, RayTable& t, std::size_t first) {
  const hn::ScalableTag<double> d;
  const hn::Rebind<float, decltype(d)> df;
  const hn::Rebind<std::int32_t, decltype(d)> di;
  const int N = static_cast<int>(hn::Lanes(d));
  const auto strides = layout.strides();
  const auto& n = layout.size;
  for (int i = 0; i < count; i += N) {
    const std::size_t e = first + static_cast<std::size_t>(i);
    const auto store_float = [&](std::vector<float>& to, hn::Vec<decltype(df)> v) {
      hn::BlendedStore(v, hn::FirstN(df, static_cast<std::size_t>(count - i)), df, to.data() + e);
    };
    const auto store_int = [&](std::vector<std::int32_t>& to, hn::Vec<decltype(di)> v) {
      hn::BlendedStore(v, hn::FirstN(di, static_cast<std::size_t>(count - i)), di, to.data() + e);
    };
    const auto to_float = [&](const double* from) { return hn::DemoteTo(df, hn::LoadU(d, from + i)); };
    const auto to_int = [&](const double* from) { return hn::DemoteTo(di, hn::LoadU(d, from + i)); };
    const auto axis = to_int(p.axis);
    const auto is0 = hn::Eq(axis, hn::Zero(di)), is1 = hn::Eq(axis, hn::Set(di, 1));
    // The value for axis 0, 1 or 2 in each lane.
    const auto pick = [&](std::ptrdiff_t x, std::ptrdiff_t y, std::ptrdiff_t z) {
      return hn::IfThenElse(
          is0, hn::Set(di, static_cast<std::int32_t>(x)),
          hn::IfThenElse(is1, hn::Set(di, static_cast<std::int32_t>(y)), hn::Set(di, static_cast<std::int32_t>(z))));
    };
    store_float(t.pb_mid, to_float(p.pb_mid));
    store_float(t.beta_b, to_float(p.beta_b));
    store_float(t.pc_mid, to_float(p.pc_mid));
    store_float(t.beta_c, to_float(p.beta_c));
    store_float(t.weight, to_float(p.weight_mm));
    store_float(t.k_mid, hn::Mul(hn::Set(df, 0.5f), hn::ConvertTo(df, pick(n[0] - 1, n[1] - 1, n[2] - 1))));
    store_int(t.k_first, to_int(p.k_first));
    store_int(t.k_last, to_int(p.k_last));
    store_int(t.axis, axis);
    // Axes b < c besides a: (1, 2), (0, 2), (0, 1).
    store_int(t.stride_a, pick(strides[0], strides[1], strides[2]));
    store_int(t.stride_b, pick(strides[1], strides[0], strides[0]));
    store_int(t.stride_c, pick(strides[2], strides[2], strides[1]));
    store_int(t.n_b, pick(n[1], n[0], n[0]));
    store_int(t.n_c, pick(n[2], n[2], n[1]));
    const auto in_first = to_int(p.in_first), in_last = to_int(p.in_last);
    const auto none = hn::Lt(in_last, in_first);  // stored as (0, -1)
    store_int(t.in_first, hn::IfThenZeroElse(none, in_first));
    store_int(t.in_last, hn::IfThenElse(none, hn::Set(di, -1), in_last));
  }
}

}  // namespace HWY_NAMESPACE
}  // namespace ctk::detail
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
namespace ctk::detail {
HWY_EXPORT(LanePixels);
HWY_EXPORT(PrepareRays);
HWY_EXPORT(StoreRays);
void prepare_rays(const ViewRays& rays, const VolumeLayout& layout, int origin_b, int origin_c, const double* u, const double* v,
                  int count, PreparedRays& out) {
  HWY_DYNAMIC_DISPATCH(PrepareRays)(rays, layout, origin_b, origin_c, u, v, count, out);
}
void lane_pixels(const LanePath& path, int line, int lane, int count, double* u, double* v) {
  HWY_DYNAMIC_DISPATCH(LanePixels)(path, line, lane, count, u, v);
}
void store_rays(const PreparedRays& p, const VolumeLayout& layout, int count, RayTable& t, std::size_t first) {
  HWY_DYNAMIC_DISPATCH(StoreRays)(p, layout, count, t, first);
}
}  // namespace ctk::detail
#endif

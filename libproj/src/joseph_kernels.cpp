// SIMD kernels of the fast Joseph projector, compiled once per x86 target by Highway and chosen
// at run time. Lanes are neighbouring rays; each lane carries its own axis, strides and range.
#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "joseph_kernels.cpp"
#include <hwy/foreach_target.h>  // IWYU pragma: keep
#include <hwy/highway.h>

#include <algorithm>

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

template <class DF>
HWY_INLINE SamplePosition<DF> position_at(DF df, const RayTable& t, std::size_t r, int k) {
  const hn::RebindToSigned<DF> di;
  const auto dk = hn::Sub(hn::Set(df, static_cast<float>(k)), hn::LoadU(df, t.k_mid.data() + r));
  const auto pb = hn::MulAdd(dk, hn::LoadU(df, t.beta_b.data() + r), hn::LoadU(df, t.pb_mid.data() + r));
  const auto pc = hn::MulAdd(dk, hn::LoadU(df, t.beta_c.data() + r), hn::LoadU(df, t.pc_mid.data() + r));
  const auto fb0 = hn::Floor(pb), fc0 = hn::Floor(pc);
  SamplePosition<DF> s;
  s.ib = hn::ConvertTo(di, fb0);
  s.ic = hn::ConvertTo(di, fc0);
  s.fb = hn::Sub(pb, fb0);
  s.fc = hn::Sub(pc, fc0);
  const auto one = hn::Set(df, 1.0f);
  s.gb = hn::Sub(one, s.fb);
  s.gc = hn::Sub(one, s.fc);
  return s;
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
  const VI base = hn::Mul(vk, sa);
  const VI ob0 = hn::Mul(hn::Min(hn::Max(ib, zero), nb1), sb), ob1 = hn::Mul(hn::Min(hn::Max(ib1, zero), nb1), sb);
  const VI oc0 = hn::Mul(hn::Min(hn::Max(ic, zero), nc1), sc), oc1 = hn::Mul(hn::Min(hn::Max(ic1, zero), nc1), sc);

  Corners<DF> out;
  out.index[0] = hn::Add(base, hn::Add(ob0, oc0));
  out.index[1] = hn::Add(base, hn::Add(ob1, oc0));
  out.index[2] = hn::Add(base, hn::Add(ob0, oc1));
  out.index[3] = hn::Add(base, hn::Add(ob1, oc1));
  out.weight[0] = hn::IfThenElseZero(hn::And(active, hn::And(vb0, vc0)), hn::Mul(p.gb, p.gc));
  out.weight[1] = hn::IfThenElseZero(hn::And(active, hn::And(vb1, vc0)), hn::Mul(p.fb, p.gc));
  out.weight[2] = hn::IfThenElseZero(hn::And(active, hn::And(vb0, vc1)), hn::Mul(p.gb, p.fc));
  out.weight[3] = hn::IfThenElseZero(hn::And(active, hn::And(vb1, vc1)), hn::Mul(p.fb, p.fc));
  return out;
}

// Same sample as corners_at for lanes known to be well inside the volume (all four corners
// valid) and inside their ray's range: identical arithmetic, no masks.
template <class DF>
HWY_INLINE Corners<DF> interior_corners_at(DF df, const RayTable& t, std::size_t r, int k) {
  const hn::RebindToSigned<DF> di;
  using VI = hn::Vec<decltype(di)>;
  const VI vk = hn::Set(di, k);
  const SamplePosition<DF> p = position_at(df, t, r, k);
  const VI sb = hn::LoadU(di, t.stride_b.data() + r), sc = hn::LoadU(di, t.stride_c.data() + r);
  const VI i00 = hn::Add(hn::Mul(vk, hn::LoadU(di, t.stride_a.data() + r)), hn::Add(hn::Mul(p.ib, sb), hn::Mul(p.ic, sc)));
  Corners<DF> out;
  out.index[0] = i00;
  out.index[1] = hn::Add(i00, sb);
  out.index[2] = hn::Add(i00, sc);
  out.index[3] = hn::Add(out.index[1], sc);
  out.weight[0] = hn::Mul(p.gb, p.gc);
  out.weight[1] = hn::Mul(p.fb, p.gc);
  out.weight[2] = hn::Mul(p.gb, p.fc);
  out.weight[3] = hn::Mul(p.fb, p.fc);
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
      const double p_mid = q == 0 ? t.pb_mid[i] : t.pc_mid[i], beta = q == 0 ? t.beta_b[i] : t.beta_c[i];
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

// Slices any of the N rays starting at r visits.
HWY_INLINE void slice_range(const RayTable& t, std::size_t r, std::size_t n, int& k_lo, int& k_hi) {
  k_lo = 1 << 30;
  k_hi = -(1 << 30);
  for (std::size_t l = 0; l < n; ++l) {
    if (t.k_last[r + l] < t.k_first[r + l]) continue;
    k_lo = std::min(k_lo, t.k_first[r + l]);
    k_hi = std::max(k_hi, t.k_last[r + l]);
  }
}

void ForwardRays(const RayTable& t, const float* HWY_RESTRICT volume, float* HWY_RESTRICT out) {
  const hn::ScalableTag<float> df;
  const std::size_t N = hn::Lanes(df);
  const auto all = hn::FirstN(df, N);
  for (std::size_t r = 0; r < static_cast<std::size_t>(t.count); r += N) {
    int k_lo, k_hi;
    slice_range(t, r, N, k_lo, k_hi);
    int in_lo, in_hi;
    interior_range(t, r, N, -1, in_lo, in_hi);
    auto sum = hn::Zero(df);
    auto accumulate = [&](const Corners<hn::ScalableTag<float>>& c) {
      auto s = hn::Mul(hn::GatherIndex(df, volume, c.index[0]), c.weight[0]);
      s = hn::MulAdd(hn::GatherIndex(df, volume, c.index[1]), c.weight[1], s);
      s = hn::MulAdd(hn::GatherIndex(df, volume, c.index[2]), c.weight[2], s);
      s = hn::MulAdd(hn::GatherIndex(df, volume, c.index[3]), c.weight[3], s);
      sum = hn::Add(sum, s);
    };
    for (int k = k_lo; k <= k_hi; ++k) {
      if (k == in_lo && in_lo <= in_hi) {
        for (; k <= in_hi; ++k) accumulate(interior_corners_at(df, t, r, k));
        if (k > k_hi) break;
      }
      accumulate(corners_at(df, t, r, k, all));
    }
    hn::StoreU(hn::Mul(sum, hn::LoadU(df, t.weight.data() + r)), df, out + r);
  }
}

void BackRays(const RayTable& t, int axis, int k_begin, int k_end, float* HWY_RESTRICT volume) {
  const hn::ScalableTag<float> df;
  const hn::RebindToSigned<decltype(df)> di;
  const std::size_t N = hn::Lanes(df);
  HWY_ALIGN std::int32_t index[4][kMaxLanes];
  HWY_ALIGN float weight[4][kMaxLanes];
  for (std::size_t r = 0; r < static_cast<std::size_t>(t.count); r += N) {
    const auto on_axis = hn::RebindMask(df, hn::Eq(hn::LoadU(di, t.axis.data() + r), hn::Set(di, axis)));
    if (hn::AllFalse(df, on_axis)) continue;
    int k_lo, k_hi;
    slice_range(t, r, N, k_lo, k_hi);
    k_lo = std::max(k_lo, k_begin);
    k_hi = std::min(k_hi, k_end - 1);
    const auto value = hn::Mul(hn::LoadU(df, t.value.data() + r), hn::LoadU(df, t.weight.data() + r));
    int in_lo, in_hi;
    interior_range(t, r, N, axis, in_lo, in_hi);
    // The fast path needs every lane on this axis (others would scatter outside the slab).
    if (!hn::AllTrue(df, on_axis)) in_lo = 1 << 30;
    auto scatter = [&](const Corners<hn::ScalableTag<float>>& c) {
      for (int q = 0; q < 4; ++q) {
        hn::Store(c.index[q], di, index[q]);
        hn::Store(hn::Mul(c.weight[q], value), df, weight[q]);
      }
      // Scalar scatter: neighbouring lanes often share a voxel. A zero weight is skipped, which
      // also keeps lanes of other axes from touching voxels outside this slab.
      for (std::size_t l = 0; l < N; ++l)
        for (int q = 0; q < 4; ++q)
          if (weight[q][l] != 0.0f) volume[index[q][l]] += weight[q][l];
    };
    for (int k = k_lo; k <= k_hi; ++k) {
      if (k >= in_lo && k <= in_hi) {
        scatter(interior_corners_at(df, t, r, k));
      } else {
        scatter(corners_at(df, t, r, k, on_axis));
      }
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

// Counts to line integrals, -log((I - dark) / (flat - dark)), one SIMD kernel per x86 target
// (Highway, chosen at run time): every projection of a counts scan passes through here, and the
// scalar logarithm was a tenth of a view's calibration (perf on ctk calibrate, 120 views of 720 x 720).
#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "line_integrals.cpp"
// Highway's order, not the alphabet's: foreach_target.h, highway.h, then the -inl headers.
// clang-format off
#include <hwy/foreach_target.h>  // IWYU pragma: keep
#include <hwy/highway.h>
#include <hwy/contrib/math/math-inl.h>
// clang-format on

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>

#include "ctk/measure/projection_reading.hpp"

#ifndef CTK_MEASURE_LINE_INTEGRALS_DEFINED
#define CTK_MEASURE_LINE_INTEGRALS_DEFINED
namespace ctk::detail {
// A transmission above 1.5 cannot come from attenuation: treat it like one at or below zero.
constexpr float kMinCounts = 0.5f, kMaxTransmission = 1.5f;

// One pixel, the definition the SIMD kernel follows lane by lane. Returns whether it was clamped.
inline bool line_integral(float counts, float flat, float dark, float& p, float* w) {
  const float open = flat - dark, detected = counts - dark;
  const float relative = std::max(detected, kMinCounts) / open;
  float t = open > 0 ? relative : kMaxTransmission;
  // A count that is not finite (NaN, +Inf, -Inf) is not clamped: its line integral is NaN, which
  // mask_non_finite masks and counts, once (a +Inf count clamped to the flat gave weight +Inf).
  const bool finite = std::isfinite(counts);
  const bool clamped = finite && (open <= 0 || detected < kMinCounts || t > kMaxTransmission);
  if (clamped) t = std::clamp(t, kMinCounts / std::max(open, 1.0f), kMaxTransmission);
  p = finite ? -std::log(t) : std::numeric_limits<float>::quiet_NaN();
  if (w) *w = open > 0 ? relative : 0.0f;
  return clamped;
}
}  // namespace ctk::detail
#endif

HWY_BEFORE_NAMESPACE();
namespace ctk::detail {
namespace HWY_NAMESPACE {
namespace hn = hwy::HWY_NAMESPACE;

std::size_t LineIntegrals(const float* counts, const float* flat, const float* dark, std::size_t n, float* p, float* w) {
  const hn::ScalableTag<float> d;
  const std::size_t N = hn::Lanes(d);
  const auto zero = hn::Zero(d), one = hn::Set(d, 1.0f), min_counts = hn::Set(d, kMinCounts),
             max_t = hn::Set(d, kMaxTransmission), nan_value = hn::Set(d, std::numeric_limits<float>::quiet_NaN());
  std::size_t clamped = 0, i = 0;
  for (; i + N <= n; i += N) {
    const auto c = hn::LoadU(d, counts + i), dk = hn::LoadU(d, dark + i);
    const auto open = hn::Sub(hn::LoadU(d, flat + i), dk), detected = hn::Sub(c, dk);
    const auto relative = hn::Div(hn::Max(detected, min_counts), open);
    const auto lit = hn::Gt(open, zero);
    auto t = hn::IfThenElse(lit, relative, max_t);
    const auto unusable = hn::Not(hn::IsFinite(c));  // NaN or infinite: NaN out, masked later
    const auto bad = hn::AndNot(unusable, hn::Or(hn::Not(lit), hn::Or(hn::Lt(detected, min_counts), hn::Gt(t, max_t))));
    clamped += hn::CountTrue(d, bad);
    const auto low = hn::Div(min_counts, hn::Max(open, one));
    t = hn::IfThenElse(bad, hn::Min(hn::Max(t, low), max_t), t);
    hn::StoreU(hn::IfThenElse(unusable, nan_value, hn::Neg(hn::Log(d, t))), d, p + i);
    if (w) hn::StoreU(hn::IfThenElseZero(lit, relative), d, w + i);
  }
  for (; i < n; ++i) clamped += line_integral(counts[i], flat[i], dark[i], p[i], w ? w + i : nullptr);
  return clamped;
}

}  // namespace HWY_NAMESPACE
}  // namespace ctk::detail
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
namespace ctk {
namespace detail {
HWY_EXPORT(LineIntegrals);
}  // namespace detail

void counts_to_line_integrals(const Image& counts, const Image& flat, const Image& dark, float* p, float* w,
                              std::size_t& clamped) {
  clamped += HWY_DYNAMIC_DISPATCH(detail::LineIntegrals)(counts.pixels.data(), flat.pixels.data(), dark.pixels.data(),
                                                         counts.pixels.size(), p, w);
}

}  // namespace ctk
#endif

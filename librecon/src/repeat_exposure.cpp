#include "ctk/recon/repeat_exposure.hpp"

#include <cmath>
#include <cstddef>

namespace ctk {

namespace {

const float* row(const FanSinogram& s, int view) {
  return s.values.data() + static_cast<std::size_t>(view) * static_cast<std::size_t>(s.cols);
}

// Mean squared difference of row a against row b read `shift` pixels on (linear interpolation),
// over the columns both cover.
double mean_square_difference(const FanSinogram& s, const float* a, const float* b, double shift) {
  double sum = 0;
  int n = 0;
  for (int u = 0; u < s.cols; ++u) {
    const double x = u + shift;
    const int i = static_cast<int>(std::floor(x));
    if (i < 0 || i + 1 >= s.cols) continue;
    const double f = x - i, value = (1 - f) * b[i] + f * b[i + 1], d = a[u] - value;
    sum += d * d;
    ++n;
  }
  return n > 0 ? sum / n : 0;
}

}  // namespace

std::optional<RepeatExposure> compare_repeat_exposure(const FanSinogram& s) {
  if (s.views < 3 || s.cols < 8 || s.step_rad == 0) return std::nullopt;
  const double covered = std::abs(s.step_rad) * (s.views - 1);
  if (std::abs(covered - 2 * M_PI) > 0.5 * std::abs(s.step_rad)) return std::nullopt;
  RepeatExposure r;
  r.last_view = s.views - 1;
  const float *first = row(s, 0), *last = row(s, r.last_view);
  // Whole hundredths of a pixel within 5 px, then a parabola through the best and its neighbours.
  constexpr double kStep = 0.01, kReach = 5;
  double best = mean_square_difference(s, first, last, 0), best_shift = 0;
  for (double shift = -kReach; shift <= kReach; shift += kStep)
    if (const double m = mean_square_difference(s, first, last, shift); m < best) {
      best = m;
      best_shift = shift;
    }
  const double lo = mean_square_difference(s, first, last, best_shift - kStep),
               hi = mean_square_difference(s, first, last, best_shift + kStep);
  const double curvature = lo + hi - 2 * best;
  r.shift_px = curvature > 0 ? best_shift + 0.5 * kStep * (lo - hi) / curvature : best_shift;
  r.rms_difference = std::sqrt(mean_square_difference(s, first, last, 0));
  // For a shift d of a row b read against a: var(d) = var(a - b) / sum over u of b'(u)^2, the
  // difference's variance taken from what is left at the best shift.
  double gradient_sq = 0;
  for (int u = 1; u + 1 < s.cols; ++u) {
    const double g = 0.5 * (last[u + 1] - last[u - 1]);
    gradient_sq += g * g;
  }
  const double left = mean_square_difference(s, first, last, r.shift_px);
  r.shift_sigma_px = gradient_sq > 0 ? std::sqrt(left / gradient_sq) : 0;
  return r;
}

}  // namespace ctk

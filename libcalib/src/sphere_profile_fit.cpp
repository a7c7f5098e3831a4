#include "ctk/calib/sphere_profile_fit.hpp"

#include <ceres/ceres.h>

#include <cmath>
#include <vector>

#include "small_problem.hpp"

namespace ctk {

namespace {

// The value part of an automatic-differentiation number, for decisions that need no derivative.
double value_of(double x) { return x; }
template <int N>
double value_of(const ceres::Jet<double, N>& x) {
  return x.a;
}

// The window's pixels: measured values against background plane + pixel-averaged chord profile.
struct WindowResidual {
  std::vector<Eigen::Vector2d> offsets;  // pixel centres relative to the window's centre
  std::vector<double> values;
  int subsamples;

  template <typename T>
  bool operator()(const T* centre, const T* disc, const T* plane, T* residual) const {
    // disc = {radius, amplitude}; plane = {a, b, c}: a + b du + c dv.
    const T r2 = disc[0] * disc[0];
    const double step = 1.0 / subsamples, first = -0.5 + 0.5 * step;
    const T scale = T(2.0 / (subsamples * subsamples)) * disc[1];
    for (std::size_t k = 0; k < values.size(); ++k) {
      const double du = offsets[k].x(), dv = offsets[k].y();
      T sum(0.0);
      // Most of the window lies wholly outside the disc: nothing to average there.
      const double cx = du - value_of(centre[0]), cy = dv - value_of(centre[1]);
      const double reach = value_of(disc[0]) + 0.7072;  // + half a pixel's diagonal
      if (cx * cx + cy * cy < reach * reach) {
        for (int i = 0; i < subsamples; ++i) {
          const T y = T(dv + first + i * step) - centre[1];
          for (int j = 0; j < subsamples; ++j) {
            const T x = T(du + first + j * step) - centre[0];
            const T inside = r2 - x * x - y * y;
            if (inside > T(0.0)) sum += sqrt(inside);
          }
        }
      }
      residual[k] = T(values[k]) - (plane[0] + plane[1] * T(du) + plane[2] * T(dv) + scale * sum);
    }
    return true;
  }
};

}  // namespace

bool refine_by_profile_fit(const Image& im, double radius_px, SphereDetection& detection, const ProfileFitOptions& o) {
  const Eigen::Vector2d start = detection.uv;
  const double reach = radius_px + o.margin_px;
  const int c0 = static_cast<int>(std::floor(start.x() - reach)), c1 = static_cast<int>(std::ceil(start.x() + reach));
  const int r0 = static_cast<int>(std::floor(start.y() - reach)), r1 = static_cast<int>(std::ceil(start.y() + reach));
  if (c0 < 0 || r0 < 0 || c1 >= im.cols || r1 >= im.rows) return false;

  // Parameters relative to the starting centre keep the numbers small and well scaled.
  double centre[2] = {0, 0}, disc[2] = {radius_px, 0}, plane[3] = {0, 0, 0};
  // Start the amplitude from the peak above the window's lowest pixel.
  double low = 1e300, high = -1e300;
  auto* window = new WindowResidual{{}, {}, o.subsamples};
  for (int r = r0; r <= r1; ++r)
    for (int c = c0; c <= c1; ++c) {
      const double du = c - start.x(), dv = r - start.y();
      if (std::hypot(du, dv) > reach) continue;
      const double value = im.pixels[static_cast<std::size_t>(r) * static_cast<std::size_t>(im.cols) + static_cast<std::size_t>(c)];
      low = std::min(low, value);
      high = std::max(high, value);
      window->offsets.emplace_back(du, dv);
      window->values.push_back(value);
    }
  const int pixels = static_cast<int>(window->values.size());
  ceres::Problem problem;
  problem.AddResidualBlock(new ceres::AutoDiffCostFunction<WindowResidual, ceres::DYNAMIC, 2, 2, 3>(window, pixels), nullptr,
                           centre, disc, plane);
  plane[0] = low;
  disc[1] = std::max(high - low, 1e-6) / (2 * radius_px);
  problem.SetParameterLowerBound(disc, 0, 0.5 * radius_px);
  problem.SetParameterUpperBound(disc, 0, 2.0 * radius_px);
  const ceres::Solver::Summary summary = solve_small_problem(problem, 25);
  const Eigen::Vector2d move(centre[0], centre[1]);
  if (!summary.IsSolutionUsable() || !(disc[1] > 0) || !(move.norm() <= o.max_move_px)) return false;
  detection.uv = start + move;
  return true;
}

}  // namespace ctk

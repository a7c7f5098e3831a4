#include "ctk/calib/holder_wall.hpp"

#include <ceres/ceres.h>

#include <algorithm>
#include <cmath>
#include <mutex>

#include "ctk/core/statistics.hpp"
#include "ctk/core/parallel.hpp"
#include "ctk/proj/projection_reading.hpp"
#include "small_problem.hpp"

namespace ctk {

namespace {

struct WallSample {
  double d, inverse_sine, p;  // distance of the ray to the axis (mm), 1 / sin(angle to it), line integral
};

// One pixel's line integral under the tube model: parameters outer R, inner r, mu, and a
// background b0 + b1 (d - R) (what a sample inside or a flat-field error adds, smooth across the wall).
struct TubeResidual {
  WallSample s;
  template <typename T>
  bool operator()(const T* x, T* r) const {
    auto chord = [&](const T& radius) {
      const T inside = radius * radius - T(s.d * s.d);
      return inside > T(0.0) ? T(2.0) * sqrt(inside) : T(0.0);
    };
    r[0] = x[3] + x[4] * (T(s.d) - x[0]) + x[2] * T(s.inverse_sine) * (chord(x[0]) - chord(x[1])) - T(s.p);
    return true;
  }
};

// The pixels of one view near the tube, between the first and the last sphere along the axis and
// off every sphere's disc.
std::vector<WallSample> wall_samples(const ScanDescription& scan, const Image& image, const ViewCalibration& view,
                                     double helix_radius) {
  const Holder& holder = *scan.holder;
  const Eigen::Matrix3d K_inverse = scan.intrinsics().K().inverse();
  const Rigid& T = *view.T_camera_holder;
  const Eigen::Vector3d origin = T.translation(), axis = T.linear().col(2);
  double z_min = 1e300, z_max = -1e300;
  for (const auto& X : holder.spheres_mm) z_min = std::min(z_min, X.z()), z_max = std::max(z_max, X.z());
  const double margin = 0.15 * (z_max - z_min);
  const double magnification = scan.source_to_detector_mm / origin.norm();
  const double sphere_px = 0.5 * holder.sphere_diameter_mm * magnification / scan.detector.pitch_u_mm + 3.0;
  std::vector<Eigen::Vector2d> discs;
  for (const auto& X : holder.spheres_mm) discs.push_back(view.P->project(X));
  std::vector<WallSample> out;
  for (int v = 0; v < image.rows; v += 2)
    for (int u = 0; u < image.cols; u += 2) {
      const Eigen::Vector3d ray = (K_inverse * Eigen::Vector3d(u, v, 1)).normalized();
      // Closest approach of the ray (through the focal spot) and the axis line.
      const double b = ray.dot(axis), e = axis.dot(origin), f = ray.dot(origin), denominator = 1 - b * b;
      if (denominator < 1e-6) continue;
      const double s = (f - b * e) / denominator, t = (b * f - e) / denominator;
      if (t < z_min + margin || t > z_max - margin) continue;
      const double d = (s * ray - (origin + t * axis)).norm();
      if (d < 0.6 * helix_radius || d > 1.4 * helix_radius) continue;
      const Eigen::Vector2d pixel(u, v);
      if (std::any_of(discs.begin(), discs.end(), [&](const Eigen::Vector2d& c) { return (c - pixel).norm() < sphere_px; }))
        continue;
      out.push_back({d, 1 / std::sqrt(denominator), image.pixels[static_cast<std::size_t>(v) * image.cols + u]});
    }
  return out;
}

// The tube's radii in one view, from the declared helix radius as the outer one's first guess.
std::optional<Eigen::Vector2d> fit_view(const std::vector<WallSample>& samples, double helix_radius) {
  if (samples.size() < 200) return std::nullopt;
  double x[5] = {helix_radius, 0.9 * helix_radius, 0.0, 0.0, 0.0};
  double peak = 0;
  for (const WallSample& s : samples) peak = std::max(peak, s.p);
  x[2] = peak / (2 * std::sqrt(x[0] * x[0] - x[1] * x[1]));  // the line integral at the inner edge
  ceres::Problem problem;
  for (const WallSample& s : samples)
    problem.AddResidualBlock(new ceres::AutoDiffCostFunction<TubeResidual, 1, 5>(new TubeResidual{s}),
                             new ceres::HuberLoss(0.05 * peak), x);
  const ceres::Solver::Summary summary = solve_small_problem(problem, 100, 1e-10);
  if (!summary.IsSolutionUsable() || !(x[1] > 0.3 * helix_radius && x[1] < x[0] && x[0] < 1.4 * helix_radius && x[2] > 0))
    return std::nullopt;
  return Eigen::Vector2d(x[1], x[0]);
}

}  // namespace

std::optional<WallMeasurement> measure_holder_wall(const ScanDescription& scan, const ScanCalibration& c, int max_views) {
  if (!scan.holder) return std::nullopt;
  // Views seeing the tube from the side, spread over the scan.
  std::vector<int> side;
  for (std::size_t v = 0; v < c.views.size(); ++v) {
    const ViewCalibration& view = c.views[v];
    if (view.status != ViewStatus::ok || !view.T_camera_holder || !view.P) continue;
    if (std::abs(view.T_camera_holder->linear().col(2).z()) < std::cos(60 * M_PI / 180)) side.push_back(static_cast<int>(v));
  }
  std::vector<int> chosen;
  for (int i = 0; i < max_views && !side.empty(); ++i) {
    const int pick = side[static_cast<std::size_t>(i) * side.size() / static_cast<std::size_t>(max_views)];
    if (chosen.empty() || chosen.back() != pick) chosen.push_back(pick);
  }
  const double helix_radius = scan.holder->helix.radius_mm;
  const std::optional<FlatDark> flat_dark = read_flat_dark(scan);
  std::vector<double> inner, outer;
  std::mutex found;
  parallel_for_dynamic(static_cast<int>(chosen.size()), [&](int i) {
    const int v = chosen[static_cast<std::size_t>(i)];
    const Image image = read_line_integrals(scan, v, flat_dark);
    const auto radii = fit_view(wall_samples(scan, image, c.views[static_cast<std::size_t>(v)], helix_radius), helix_radius);
    if (!radii) return;
    const std::lock_guard<std::mutex> lock(found);
    inner.push_back(radii->x());
    outer.push_back(radii->y());
  });
  if (inner.size() < 3) return std::nullopt;
  WallMeasurement m;
  m.views = static_cast<int>(inner.size());
  // Median and its standard error from the spread (1.2533 sigma / sqrt(n) for a median).
  auto estimate = [](std::vector<double> values, double& sigma) {
    std::vector<double> deviation = values;
    const double centre = median_in_place(values);
    for (double& x : deviation) x = std::abs(x - centre);
    sigma = 1.2533 * 1.4826 * median_in_place(deviation) / std::sqrt(static_cast<double>(deviation.size()));
    return centre;
  };
  m.wall.inner_radius_mm = estimate(inner, m.inner_sigma_mm);
  m.wall.outer_radius_mm = estimate(outer, m.outer_sigma_mm);
  return m;
}

}  // namespace ctk

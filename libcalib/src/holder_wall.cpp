#include "ctk/calib/holder_wall.hpp"

#include <ceres/ceres.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <mutex>

#include "ctk/core/statistics.hpp"
#include "ctk/core/parallel.hpp"
#include "ctk/geom/nominal_geometry.hpp"
#include "ctk/proj/projection_reading.hpp"
#include "small_problem.hpp"

namespace ctk {

namespace {

// A pixel integrates the intensity over its area; near the wall's edges the chord changes
// within a pixel, so the model averages the transmission of 2 x 2 rays across it.
constexpr int rays_per_pixel = 4;

struct WallSample {
  std::array<double, rays_per_pixel> d;  // distance of each ray to the axis (mm)
  double inverse_sine, p;                // 1 / sin(angle of the ray to the axis), measured line integral
};

// One pixel's line integral under the tube model: parameters outer R, inner r, mu, and a
// background b0 + b1 (d - R) (what a sample inside or a flat-field error adds, smooth across the wall).
struct TubeResidual {
  WallSample s;
  template <typename T>
  bool operator()(const T* x, T* r) const {
    auto chord = [](const T& radius, double d) {
      const T inside = radius * radius - T(d * d);
      return inside > T(0.0) ? T(2.0) * sqrt(inside) : T(0.0);
    };
    T transmission(0.0);
    double mean_d = 0;
    for (double d : s.d) {
      transmission += exp(-x[2] * T(s.inverse_sine) * (chord(x[0], d) - chord(x[1], d)));
      mean_d += d / rays_per_pixel;
    }
    r[0] = x[3] + x[4] * (T(mean_d) - x[0]) - log(transmission / T(rays_per_pixel)) - T(s.p);
    return true;
  }
};

// The pixels of one view near the tube, between the first and the last sphere along the axis and
// off every sphere's disc.
std::vector<WallSample> wall_samples(const ScanDescription& scan, const Image& image, const ViewCalibration& view,
                                     double helix_radius) {
  const Holder& holder = *scan.holder;
  // The view's own camera (a declared drift moves its principal point) and pose in it.
  const ProjectionMatrix::Decomposition camera = view.P->decompose();
  const Eigen::Matrix3d K_inverse = camera.intrinsics.K().inverse();
  const Rigid& T = camera.T_camera_frame;
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
      // Closest approach of a ray (through the focal spot) and the axis line.
      auto closest = [&](double pu, double pv, double& along, double& denominator) {
        const Eigen::Vector3d ray = (K_inverse * Eigen::Vector3d(pu, pv, 1)).normalized();
        const double b = ray.dot(axis), e = axis.dot(origin), f = ray.dot(origin);
        denominator = 1 - b * b;
        const double s = (f - b * e) / denominator;
        along = (b * f - e) / denominator;
        return (s * ray - (origin + along * axis)).norm();
      };
      double t = 0, denominator = 0;
      const double d = closest(u, v, t, denominator);
      if (denominator < 1e-6 || t < z_min + margin || t > z_max - margin) continue;
      if (d < 0.6 * helix_radius || d > 1.4 * helix_radius) continue;
      const Eigen::Vector2d pixel(u, v);
      if (std::any_of(discs.begin(), discs.end(), [&](const Eigen::Vector2d& c) { return (c - pixel).norm() < sphere_px; }))
        continue;
      WallSample sample{{}, 1 / std::sqrt(denominator), image.pixels[static_cast<std::size_t>(v) * image.cols + u]};
      for (int k = 0; k < rays_per_pixel; ++k) {
        double ignored_t = 0, ignored_denominator = 0;
        sample.d[static_cast<std::size_t>(k)] =
            closest(u + (k % 2 - 0.5) / 2, v + (k / 2 - 0.5) / 2, ignored_t, ignored_denominator);
      }
      out.push_back(sample);
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

namespace {

// Views seeing the tube from the side (axis at least 60 deg from the beam) thin out to `count`
// spread over the scan.
std::vector<int> spread_side_views(const std::vector<std::optional<Rigid>>& poses, int count) {
  std::vector<int> side;
  for (std::size_t v = 0; v < poses.size(); ++v)
    if (poses[v] && std::abs(poses[v]->linear().col(2).z()) < std::cos(60 * M_PI / 180)) side.push_back(static_cast<int>(v));
  std::vector<int> chosen;
  for (int i = 0; i < count && !side.empty(); ++i) {
    const int pick = side[static_cast<std::size_t>(i) * side.size() / static_cast<std::size_t>(count)];
    if (chosen.empty() || chosen.back() != pick) chosen.push_back(pick);
  }
  return chosen;
}

}  // namespace

std::vector<int> wall_sample_views(const ScanDescription& scan, int count) {
  std::vector<std::optional<Rigid>> poses;
  for (const NominalView& nominal : nominal_views(scan)) {
    poses.push_back(nominal.T_camera_holder);
    if (!poses.back() && nominal.P) poses.back() = nominal.P->decompose().T_camera_frame;
  }
  return spread_side_views(poses, count);
}

std::optional<WallMeasurement> measure_holder_wall(const ScanDescription& scan, const ScanCalibration& c, int max_views) {
  if (!scan.holder) return std::nullopt;
  std::vector<std::optional<Rigid>> poses;
  for (const ViewCalibration& view : c.views)
    poses.push_back(view.status == ViewStatus::ok && view.P ? view.P->decompose().T_camera_frame : std::optional<Rigid>());
  const std::vector<int> chosen = spread_side_views(poses, max_views);
  const double helix_radius = scan.holder->helix.radius_mm;
  const std::optional<FlatDark> flat_dark = read_flat_dark(scan);
  std::vector<double> inner, outer, scale_sigma;
  std::mutex found;
  parallel_for_dynamic(static_cast<int>(chosen.size()), [&](int i) {
    const int v = chosen[static_cast<std::size_t>(i)];
    const Image image = read_line_integrals(scan, v, flat_dark);
    const auto radii = fit_view(wall_samples(scan, image, c.views[static_cast<std::size_t>(v)], helix_radius), helix_radius);
    if (!radii) return;
    const std::lock_guard<std::mutex> lock(found);
    inner.push_back(radii->x());
    outer.push_back(radii->y());
    const ViewCalibration& view = c.views[static_cast<std::size_t>(v)];
    scale_sigma.push_back(view.translation_sigma_mm[2] / view.P->decompose().T_camera_frame.translation().norm());
  });
  if (inner.size() < 3) return std::nullopt;
  WallMeasurement m;
  m.views = static_cast<int>(inner.size());
  // The radii are lengths in the views' frames, whose scale is the magnification, known as well
  // as each view's depth along the beam. A depth error shared by the views (a bias of the sphere
  // centres) is not averaged away by their number, so it enters the uncertainty undivided.
  const double scale = median_in_place(scale_sigma);
  // Median and its standard error from the spread (1.2533 sigma / sqrt(n) for a median).
  auto estimate = [scale](std::vector<double> values, double& sigma) {
    std::vector<double> deviation = values;
    const double centre = median_in_place(values);
    for (double& x : deviation) x = std::abs(x - centre);
    const double spread = 1.2533 * 1.4826 * median_in_place(deviation) / std::sqrt(static_cast<double>(deviation.size()));
    sigma = std::hypot(spread, scale * centre);
    return centre;
  };
  m.wall.inner_radius_mm = estimate(inner, m.inner_sigma_mm);
  m.wall.outer_radius_mm = estimate(outer, m.outer_sigma_mm);
  return m;
}

nlohmann::json to_json(const WallMeasurement& m) {
  return {{"inner_radius_mm", m.wall.inner_radius_mm},
          {"outer_radius_mm", m.wall.outer_radius_mm},
          {"inner_sigma_mm", m.inner_sigma_mm},
          {"outer_sigma_mm", m.outer_sigma_mm},
          {"views", m.views}};
}

}  // namespace ctk

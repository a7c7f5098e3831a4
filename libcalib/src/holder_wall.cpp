#include "ctk/calib/holder_wall.hpp"

#include <ceres/ceres.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <mutex>
#include <sstream>

#include "ctk/core/parallel.hpp"
#include "ctk/core/statistics.hpp"
#include "ctk/geom/nominal_geometry.hpp"
#include "ctk/measure/projection_reading.hpp"
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

// One view's rays in the holder frame: through a pixel (or a point within one), where such a ray
// passes closest to the holder's axis, and whether a pixel lies on a sphere's disc.
class ViewRays {
 public:
  ViewRays(const Holder& holder, const ProjectionMatrix& P)
      // P is scaled to give positive depths, so M^-1 (u, v, 1) points away from the source (as
      // ray_direction has it); the inverse is taken once.
      : source_(P.source_position()), M_inverse_(P.matrix().leftCols<3>().inverse()) {
    for (const auto& X : holder.spheres_mm) discs_.push_back(P.project(X));
    const ProjectionMatrix::Decomposition camera = P.decompose();
    const double px_per_mm = std::abs(camera.intrinsics.K()(0, 0)) / camera.T_camera_frame.translation().norm();
    disc_px_ = 0.5 * holder.sphere_diameter_mm * px_per_mm + 3.0;
  }

  const Eigen::Vector3d& source() const { return source_; }
  Eigen::Vector3d ray(double u, double v) const { return (M_inverse_ * Eigen::Vector3d(u, v, 1)).normalized(); }

  struct Approach {
    double d = 0, along = 0;  // distance to the axis and where along it (mm)
    double sine = 0;          // of the ray's angle to the axis
  };
  /// None for a ray (nearly) along the axis.
  std::optional<Approach> approach(const Eigen::Vector3d& ray) const {
    const double b = ray.z(), denominator = 1 - b * b;
    if (denominator < 1e-6) return std::nullopt;
    const Eigen::Vector3d closest = source_ + ((-source_.dot(ray) + b * source_.z()) / denominator) * ray;
    return Approach{closest.head<2>().norm(), closest.z(), std::sqrt(denominator)};
  }

  bool on_a_sphere(const Eigen::Vector2d& pixel) const {
    return std::any_of(discs_.begin(), discs_.end(), [&](const Eigen::Vector2d& c) { return (c - pixel).norm() < disc_px_; });
  }

  /// The point k of a pixel's 2 x 2 rays.
  static Eigen::Vector2d sub_ray(int u, int v, int k) {
    const int column = k % 2, row = k / 2;  // of the 2 x 2 sub-rays
    return {u + (column - 0.5) / 2, v + (row - 0.5) / 2};
  }

 private:
  Eigen::Vector3d source_;
  Eigen::Matrix3d M_inverse_;
  std::vector<Eigen::Vector2d> discs_;
  double disc_px_ = 0;
};

// The pixels of one view near the tube, between the first and the last sphere along the axis and
// off every sphere's disc.
std::vector<WallSample> wall_samples(const Holder& holder, const Image& image, const ViewCalibration& view, double helix_radius) {
  const ViewRays rays(holder, *view.P);
  const double z_min = holder.tau_min(), z_max = holder.tau_max(), margin = 0.15 * (z_max - z_min);
  std::vector<WallSample> out;
  for (int v = 0; v < image.rows; v += 2)
    for (int u = 0; u < image.cols; u += 2) {
      const auto a = rays.approach(rays.ray(u, v));
      if (!a || a->along < z_min + margin || a->along > z_max - margin) continue;
      if (a->d < 0.6 * helix_radius || a->d > 1.4 * helix_radius || rays.on_a_sphere({u, v})) continue;
      WallSample sample{{}, 1 / a->sine, image.pixels[static_cast<std::size_t>(v) * image.cols + u]};
      for (int k = 0; k < rays_per_pixel; ++k) {
        const Eigen::Vector2d sub = ViewRays::sub_ray(u, v, k);
        const auto sub_approach = rays.approach(rays.ray(sub.x(), sub.y()));
        sample.d[static_cast<std::size_t>(k)] = sub_approach ? sub_approach->d : a->d;
      }
      out.push_back(sample);
    }
  return out;
}

// The tube in one view: TubeResidual's parameters (outer and inner radius, attenuation, background).
struct TubeFit {
  double outer = 0, inner = 0, mu = 0, b0 = 0, b1 = 0;
  double robust_scale = 0;  // of the residuals, for the ends' fit
};

// The tube's radii in one view, from the declared helix radius as the outer one's first guess.
std::optional<TubeFit> fit_view(const std::vector<WallSample>& samples, double helix_radius) {
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
  return TubeFit{x[0], x[1], x[2], x[3], x[4], 0.05 * peak};
}

// Where a ray runs inside the wall of an infinitely long tube: up to two stretches of the holder's
// w, each with its path length (a ray square to the axis has its whole chord at one w).
struct RayInWall {
  struct Stretch {
    double low = 0, high = 0, length = 0;
  };
  std::array<Stretch, 2> stretches;
  int count = 0;

  RayInWall(const Eigen::Vector3d& origin, const Eigen::Vector3d& direction, double inner, double outer) {
    const double a = direction.head<2>().squaredNorm(), b = origin.head<2>().dot(direction.head<2>());
    const double c = origin.head<2>().squaredNorm();
    auto crossing = [&](double r, double& t0, double& t1) {
      const double discriminant = b * b - a * (c - r * r);
      if (a < 1e-24 || discriminant <= 0) return false;
      t0 = (-b - std::sqrt(discriminant)) / a;
      t1 = (-b + std::sqrt(discriminant)) / a;
      return true;
    };
    double t0 = 0, t1 = 0, s0 = 0, s1 = 0;
    if (!crossing(outer, t0, t1)) return;
    auto add = [&](double from, double to) {
      const double w0 = origin.z() + from * direction.z(), w1 = origin.z() + to * direction.z();
      stretches[static_cast<std::size_t>(count++)] = {std::min(w0, w1), std::max(w0, w1), to - from};
    };
    if (crossing(inner, s0, s1)) {
      add(t0, s0);
      add(s1, t1);
    } else {
      add(t0, t1);
    }
  }

  /// Path length in the wall on the tube's side of an end at w = `end` (side -1: the lower end,
  /// the tube above it; +1: the upper end).
  double chord(double end, int side) const {
    double sum = 0;
    for (int i = 0; i < count; ++i) {
      const Stretch& s = stretches[static_cast<std::size_t>(i)];
      const double span = s.high - s.low;
      const double kept = side < 0 ? s.high - std::max(s.low, end) : std::min(s.high, end) - s.low;
      sum += span > 1e-12 ? s.length * std::clamp(kept / span, 0.0, 1.0)
                          : ((side < 0 ? s.low >= end : s.low <= end) ? s.length : 0.0);
    }
    return sum;
  }
};

struct EndSample {
  std::vector<RayInWall> rays;  // rays_per_pixel of them
  double mean_d = 0, p = 0;
  double low = 1e300, high = -1e300;  // the w its rays spend in the wall
};

// The pixels beyond one end of the spheres' band whose rays pass within the wall's radii (never
// through the bore, where a sample may be), and how far along the axis the last of them looks.
struct EndSamples {
  std::vector<EndSample> samples;
  double farthest = 0;
};

// Both ends' pixels of one view in one pass over the detector: [0] below the lowest sphere, [1]
// above the highest.
std::array<EndSamples, 2> end_samples(const Holder& holder, const Image& image, const ViewCalibration& view,
                                      const TubeFit& tube) {
  const ViewRays rays(holder, *view.P);
  const double band_low = holder.tau_min(), band_high = holder.tau_max();
  std::array<EndSamples, 2> ends;
  ends[0].farthest = band_low;
  ends[1].farthest = band_high;
  for (int v = 0; v < image.rows; ++v)
    for (int u = 0; u < image.cols; ++u) {
      const auto a = rays.approach(rays.ray(u, v));
      if (!a || a->d < tube.inner || a->d > tube.outer || (a->along >= band_low && a->along <= band_high)) continue;
      if (rays.on_a_sphere({u, v})) continue;
      EndSample sample;
      for (int k = 0; k < rays_per_pixel; ++k) {
        const Eigen::Vector2d sub = ViewRays::sub_ray(u, v, k);
        sample.rays.emplace_back(rays.source(), rays.ray(sub.x(), sub.y()), tube.inner, tube.outer);
      }
      sample.mean_d = a->d;
      sample.p = image.pixels[static_cast<std::size_t>(v) * static_cast<std::size_t>(image.cols) + static_cast<std::size_t>(u)];
      for (const RayInWall& r : sample.rays)
        for (int i = 0; i < r.count; ++i) {
          sample.low = std::min(sample.low, r.stretches[static_cast<std::size_t>(i)].low);
          sample.high = std::max(sample.high, r.stretches[static_cast<std::size_t>(i)].high);
        }
      EndSamples& end = ends[a->along < band_low ? 0 : 1];
      end.samples.push_back(std::move(sample));
      end.farthest = a->along < band_low ? std::min(end.farthest, a->along) : std::max(end.farthest, a->along);
    }
  return ends;
}

// The tube's end beyond the spheres on one side (-1: below the lowest, +1: above the highest) in
// one view: each of that end's pixels (end_samples) predicted by the view's fitted tube cut at
// w = e; e chosen by least squares (Huber), on a 2 mm grid out to the last such pixel, then
// 0.5 mm around its best node, then by golden section to 0.005 mm. None when the best end lies
// within 2 mm of where the view stops seeing the tube (it runs off the detector) or the cut
// explains nothing.
std::optional<double> fit_end(const EndSamples& pixels, const TubeFit& tube, double band_edge, int side) {
  const std::vector<EndSample>& samples = pixels.samples;
  const double farthest = pixels.farthest;
  if (samples.size() < 100) return std::nullopt;
  const double huber = tube.robust_scale;
  auto loss = [&](const EndSample& s, double cut) {
    double transmission = 0;
    for (const RayInWall& r : s.rays) transmission += std::exp(-tube.mu * r.chord(cut, side));
    const double residual = s.p - (tube.b0 + tube.b1 * (s.mean_d - tube.outer) - std::log(transmission / rays_per_pixel));
    const double a = std::abs(residual);
    return a <= huber ? residual * residual : huber * (2 * a - huber);
  };
  // An end beyond a pixel's stretch of wall leaves all of it or none: those two losses once, so a
  // trial end computes only the pixels whose wall it cuts.
  std::vector<double> loss_whole(samples.size()), loss_none(samples.size());
  for (std::size_t i = 0; i < samples.size(); ++i) {
    const EndSample& s = samples[i];
    loss_whole[i] = loss(s, side < 0 ? s.low - 1 : s.high + 1);
    loss_none[i] = loss(s, side < 0 ? s.high + 1 : s.low - 1);
  }
  auto cost = [&](double e) {
    double sum = 0;
    for (std::size_t i = 0; i < samples.size(); ++i) {
      const EndSample& s = samples[i];
      if (e <= s.low)
        sum += side < 0 ? loss_whole[i] : loss_none[i];
      else if (e >= s.high)
        sum += side < 0 ? loss_none[i] : loss_whole[i];
      else
        sum += loss(s, e);
    }
    return sum;
  };
  // The cost grows about linearly with the distance from the true end (the pixels between them
  // predicted wrong): a coarse grid, then a fine one around its best node.
  constexpr double kCoarseMm = 2.0, kFineMm = 0.5;
  double best_end = band_edge, best = cost(band_edge);
  for (double e = band_edge + side * kCoarseMm; side * (e - farthest) < 0; e += side * kCoarseMm)
    if (const double c = cost(e); c < best) best = c, best_end = e;
  const double coarse_best = best_end;
  for (double e = coarse_best - kCoarseMm + kFineMm; e < coarse_best + kCoarseMm; e += kFineMm)
    if (side * (e - band_edge) >= 0 && side * (e - farthest) < 0)
      if (const double c = cost(e); c < best) best = c, best_end = e;
  if (side * (farthest - best_end) < 2 || !(best < cost(farthest + side * 1e6))) return std::nullopt;
  // Golden section over the fine step either side of the best node.
  double lo = best_end - kFineMm, hi = best_end + kFineMm;
  const double g = 0.5 * (std::sqrt(5.0) - 1);
  double x1 = hi - g * (hi - lo), x2 = lo + g * (hi - lo), f1 = cost(x1), f2 = cost(x2);
  while (hi - lo > 0.005) {
    if (f1 < f2) {
      hi = x2, x2 = x1, f2 = f1, x1 = hi - g * (hi - lo), f1 = cost(x1);
    } else {
      lo = x1, x1 = x2, f1 = f2, x2 = lo + g * (hi - lo), f2 = cost(x2);
    }
  }
  return 0.5 * (lo + hi);
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
  std::vector<double> inner, outer, scale_sigma, lower, upper, lower_scale, upper_scale;
  std::mutex found;
  parallel_for_dynamic(static_cast<int>(chosen.size()), [&](int i) {
    const int v = chosen[static_cast<std::size_t>(i)];
    const ViewCalibration& view = c.views[static_cast<std::size_t>(v)];
    const Image image = read_line_integrals(scan, v, flat_dark);
    const auto tube = fit_view(wall_samples(*scan.holder, image, view, helix_radius), helix_radius);
    if (!tube) return;
    const std::array<EndSamples, 2> ends = end_samples(*scan.holder, image, view, *tube);
    const auto lower_end = fit_end(ends[0], *tube, scan.holder->tau_min(), -1),
               upper_end = fit_end(ends[1], *tube, scan.holder->tau_max(), 1);
    const double scale = view.translation_sigma_mm[2] / view.P->decompose().T_camera_frame.translation().norm();
    const std::lock_guard<std::mutex> lock(found);
    inner.push_back(tube->inner);
    outer.push_back(tube->outer);
    scale_sigma.push_back(scale);
    if (lower_end) lower.push_back(*lower_end), lower_scale.push_back(scale);
    if (upper_end) upper.push_back(*upper_end), upper_scale.push_back(scale);
  });
  if (inner.size() < 3) return std::nullopt;
  WallMeasurement m;
  m.views = static_cast<int>(inner.size());
  // The radii are lengths in the views' frames, whose scale is the magnification, known as well
  // as each view's depth along the beam. A depth error shared by the views (a bias of the sphere
  // centres) is not averaged away by their number, so it enters the uncertainty undivided.
  // Median and its standard error from the spread (1.2533 sigma / sqrt(n) for a median).
  auto estimate = [](std::vector<double> values, std::vector<double> scales, double& sigma) {
    const double scale = median_in_place(scales);
    std::vector<double> deviation = values;
    const double centre = median_in_place(values);
    for (double& x : deviation) x = std::abs(x - centre);
    const double spread = 1.2533 * 1.4826 * median_in_place(deviation) / std::sqrt(static_cast<double>(deviation.size()));
    sigma = std::hypot(spread, scale * centre);
    return centre;
  };
  m.wall.inner_radius_mm = estimate(inner, scale_sigma, m.inner_sigma_mm);
  m.wall.outer_radius_mm = estimate(outer, scale_sigma, m.outer_sigma_mm);
  // The ends when at least 3 views see each (a tube longer than the field of view shows none).
  if (lower.size() >= 3 && upper.size() >= 3) {
    Eigen::Vector2d ends, sigma;
    ends.x() = estimate(lower, lower_scale, sigma.x());
    ends.y() = estimate(upper, upper_scale, sigma.y());
    m.wall.ends_mm = ends;
    m.ends_sigma_mm = sigma;
    m.end_views = static_cast<int>(std::min(lower.size(), upper.size()));
  }
  return m;
}

bool wall_to_measure(const ScanDescription& scan) { return scan.holder && (!scan.holder->wall || !scan.holder->wall->ends_mm); }

HolderWall modelled_wall(const ScanDescription& scan, const WallMeasurement& measured) {
  if (!scan.holder || !scan.holder->wall) return measured.wall;
  HolderWall wall = *scan.holder->wall;
  if (!wall.ends_mm) wall.ends_mm = measured.wall.ends_mm;
  return wall;
}

std::string wall_line(const std::optional<HolderWall>& declared, const std::optional<WallMeasurement>& measured) {
  if (declared && declared->ends_mm) return "";
  std::ostringstream b;
  b.precision(4);
  const bool ends = measured && measured->wall.ends_mm;
  if (declared)
    b << "holder wall declared without its ends";
  else if (measured)
    b << "holder wall not declared by the scan; measured in " << measured->views << " views: inner radius "
      << measured->wall.inner_radius_mm << " +- " << measured->inner_sigma_mm << " mm, outer " << measured->wall.outer_radius_mm
      << " +- " << measured->outer_sigma_mm << " mm";
  else
    return "holder wall not declared by the scan and not measurable (fewer than 3 views see the holder from the side)";
  if (ends)
    b << "; its ends measured in " << measured->end_views << " views at " << measured->wall.ends_mm->x() << " +- "
      << measured->ends_sigma_mm->x() << " and " << measured->wall.ends_mm->y() << " +- " << measured->ends_sigma_mm->y()
      << " mm along the axis (declare holder.wall with ends_mm to skip this)";
  else
    b << "; its ends seen in too few views (modelled as an infinitely long tube, and within about 5 deg of its axis, "
         "where the ends decide its shadow, views are calibrated without it)";
  return b.str();
}

nlohmann::json to_json(const WallMeasurement& m) {
  nlohmann::json j = {{"inner_radius_mm", m.wall.inner_radius_mm},
                      {"outer_radius_mm", m.wall.outer_radius_mm},
                      {"inner_sigma_mm", m.inner_sigma_mm},
                      {"outer_sigma_mm", m.outer_sigma_mm},
                      {"views", m.views}};
  if (m.wall.ends_mm)
    j["ends"] = {{"ends_mm", {m.wall.ends_mm->x(), m.wall.ends_mm->y()}},
                 {"ends_sigma_mm", {m.ends_sigma_mm->x(), m.ends_sigma_mm->y()}},
                 {"views", m.end_views}};
  else
    j["ends"] = nullptr;
  return j;
}

}  // namespace ctk

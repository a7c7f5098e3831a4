#include "ctk/calib/sphere_profile_fit.hpp"
#include "ctk/core/error.hpp"

#include <ceres/ceres.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <vector>

#include "small_problem.hpp"

namespace ctk {

namespace {

// The window's pixels: measured values against the background (plane + scaled known shape) plus
// each ball's pixel-averaged chord profile. The model is a sum of square roots, so its derivatives
// are written out: automatic differentiation cost several times more here, in the fit that
// dominates a view's calibration.
// Parameter blocks: the balls' centres (u, v each); their discs (radius, amplitude each); the
// background {a, b, c, s}: a + b du + c dv + s shape.
class WindowCost : public ceres::CostFunction {
 public:
  WindowCost(std::vector<Eigen::Vector2d> offsets, std::vector<double> values, std::vector<double> shape, int balls,
             int subsamples, double contrast_loss, double reference_background)
      : offsets_(std::move(offsets)),
        values_(std::move(values)),
        shape_(std::move(shape)),
        balls_(balls),
        subsamples_(subsamples),
        contrast_loss_(contrast_loss),
        reference_(reference_background) {
    mutable_parameter_block_sizes()->assign({2 * balls, 2 * balls, 4});
    set_num_residuals(static_cast<int>(values_.size()));
  }

  bool Evaluate(double const* const* p, double* residual, double** jacobians) const override {
    const double* centre = p[0];
    const double* disc = p[1];
    const double* background = p[2];
    const int n = num_residuals(), width = 2 * balls_;
    double* j_centre = jacobians ? jacobians[0] : nullptr;
    double* j_disc = jacobians ? jacobians[1] : nullptr;
    double* j_background = jacobians ? jacobians[2] : nullptr;
    if (j_centre) std::fill(j_centre, j_centre + n * width, 0.0);
    if (j_disc) std::fill(j_disc, j_disc + n * width, 0.0);
    const double step = 1.0 / subsamples_, first = -0.5 + 0.5 * step;
    const double weight = 2.0 / (subsamples_ * subsamples_);  // chord = 2 sqrt(.), averaged
    for (int k = 0; k < n; ++k) {
      const auto ku = static_cast<std::size_t>(k);
      const double du = offsets_[ku].x(), dv = offsets_[ku].y();
      const double under = background[0] + background[1] * du + background[2] * dv + background[3] * shape_[ku];
      // The balls' contrast falls by `contrast_loss` per unit of background line integral above
      // the window's reference (a spectrum hardened by the wall, scatter): each chord is scaled by
      // `contrast`, so a ball on a steep background is no longer pulled towards its thinner side.
      const double contrast = 1.0 - contrast_loss_ * (under - reference_);
      double model = under, balls_sum = 0;  // balls_sum: the balls' unscaled sum, for the background's derivatives
      for (int b = 0; b < balls_; ++b) {
        const double cu = centre[2 * b], cv = centre[2 * b + 1], radius = disc[2 * b], amplitude = disc[2 * b + 1];
        // Most of the window lies wholly outside a given disc: nothing to average there.
        const double reach = radius + 0.7072;  // + half a pixel's diagonal
        if ((du - cu) * (du - cu) + (dv - cv) * (dv - cv) >= reach * reach) continue;
        double chord = 0, d_u = 0, d_v = 0, d_radius = 0;  // sums of sqrt and of its derivatives / 1
        for (int i = 0; i < subsamples_; ++i) {
          const double y = dv + first + i * step - cv;
          for (int j = 0; j < subsamples_; ++j) {
            const double x = du + first + j * step - cu;
            const double inside = radius * radius - x * x - y * y;
            if (inside <= 0) continue;
            const double root = std::sqrt(inside);
            chord += root;
            d_u += x / root;  // d root / d cu
            d_v += y / root;
            d_radius += radius / root;
          }
        }
        model += contrast * weight * amplitude * chord;
        balls_sum += weight * amplitude * chord;
        if (j_centre) {
          j_centre[k * width + 2 * b] = -contrast * weight * amplitude * d_u;
          j_centre[k * width + 2 * b + 1] = -contrast * weight * amplitude * d_v;
        }
        if (j_disc) {
          j_disc[k * width + 2 * b] = -contrast * weight * amplitude * d_radius;
          j_disc[k * width + 2 * b + 1] = -contrast * weight * chord;
        }
      }
      if (j_background) {
        const double scale = 1.0 - contrast_loss_ * balls_sum;  // d model / d under
        double* row = j_background + 4 * k;
        row[0] = -scale;
        row[1] = -scale * du;
        row[2] = -scale * dv;
        row[3] = -scale * shape_[ku];
      }
      residual[k] = values_[ku] - model;
    }
    return true;
  }

 private:
  std::vector<Eigen::Vector2d> offsets_;  // pixel centres relative to the window's reference point
  std::vector<double> values_;
  std::vector<double> shape_;  // the known background shape, pixel-averaged (0 if none)
  int balls_;
  int subsamples_;
  double contrast_loss_;
  double reference_;
};

// The known shape averaged over each pixel of the window [c0, c1] x [r0, r1] (row-major). Where it
// is smooth, the centre f and the mean m of the four corners give the average to third order,
// (2 f + m) / 3 (exact for a quadratic), with the corners shared between neighbours: two
// evaluations per pixel. Near the wall's silhouettes the chord has square-root edges of infinite
// slope; there (f and m disagree by more than 0.2 % of the shape, or the shape starts within the
// pixel) it is averaged over a 4 x 4 grid. Without a shape, every average is 0.
class PixelAverages {
 public:
  PixelAverages(const BackgroundShape& shape, int c0, int r0, int c1, int r1)
      : shape_(shape), c0_(c0), r0_(r0), width_(c1 - c0 + 2) {
    if (!shape) return;
    corners_.resize(static_cast<std::size_t>(width_ * (r1 - r0 + 2)));
    for (int r = r0; r <= r1 + 1; ++r)
      for (int c = c0; c <= c1 + 1; ++c) corners_[index(c, r)] = shape({c - 0.5, r - 0.5});
  }

  double operator()(int c, int r) const {
    if (!shape_) return 0.0;
    const double centre = shape_({c, r});
    const double a = corners_[index(c, r)], b = corners_[index(c + 1, r)], d = corners_[index(c, r + 1)],
                 e = corners_[index(c + 1, r + 1)];
    const double lowest = std::min({centre, a, b, d, e}), highest = std::max({centre, a, b, d, e});
    const double mean = 0.25 * (a + b + d + e);
    const bool starts_here = (lowest == 0) != (highest == 0);
    if (!starts_here && std::abs(mean - centre) <= 2e-3 * std::max(std::abs(lowest), std::abs(highest)))
      return (2 * centre + mean) / 3;
    constexpr int kSubsamples = 4;
    double sum = 0;
    for (int i = 0; i < kSubsamples; ++i)
      for (int j = 0; j < kSubsamples; ++j) sum += shape_({c - 0.5 + (j + 0.5) / kSubsamples, r - 0.5 + (i + 0.5) / kSubsamples});
    return sum / (kSubsamples * kSubsamples);
  }

 private:
  std::size_t index(int c, int r) const { return static_cast<std::size_t>((r - r0_) * width_ + (c - c0_)); }
  const BackgroundShape& shape_;
  int c0_, r0_, width_;
  std::vector<double> corners_;
};

// The pixels within `reach` of some ball's start in the box [c0, c1] x [r0, r1], as offsets from
// `origin`, with their values and the background shape's.
struct WindowPixels {
  std::vector<Eigen::Vector2d> offsets;
  std::vector<double> values, shape_values;
  std::vector<bool> clear;  // no ball within a pixel of it: what the starting background is fitted to
};

WindowPixels window_pixels(const Image& im, std::span<const SphereDetection> spheres, const Eigen::Vector2d& origin, double reach,
                           double radius_px, const PixelAverages& shape_average, int c0, int r0, int c1, int r1) {
  WindowPixels w;
  for (int r = r0; r <= r1; ++r)
    for (int c = c0; c <= c1; ++c) {
      const Eigen::Vector2d pixel(c, r);
      double nearest = 1e300;
      for (const auto& s : spheres) nearest = std::min(nearest, (pixel - s.uv).norm());
      if (nearest > reach) continue;
      w.offsets.push_back(pixel - origin);
      w.values.push_back(
          im.pixels[static_cast<std::size_t>(r) * static_cast<std::size_t>(im.cols) + static_cast<std::size_t>(c)]);
      w.shape_values.push_back(shape_average(c, r));
      w.clear.push_back(nearest > radius_px + 1);
    }
  return w;
}

}  // namespace

void ProfileFitOptions::validate() const {
  require_option(margin_px > 0, "ProfileFitOptions.margin_px", "a number above 0", margin_px);
  require_option(subsamples >= 1, "ProfileFitOptions.subsamples", "at least 1", subsamples);
  require_option(max_move_px > 0, "ProfileFitOptions.max_move_px", "a number above 0", max_move_px);
  require_option(std::isfinite(contrast_loss), "ProfileFitOptions.contrast_loss", "a finite number", contrast_loss);
}

std::vector<bool> refine_cluster_by_profile_fit(const Image& im, double radius_px, std::span<SphereDetection> spheres,
                                                const ProfileFitOptions& o, const BackgroundShape& shape) {
  o.validate();
  const int n = static_cast<int>(spheres.size());
  std::vector<bool> refined(spheres.size(), false);
  if (n == 0) return refined;
  const double reach = radius_px + o.margin_px;
  // The window: every pixel within `reach` of some ball's start, in a box that must lie on the image.
  Eigen::AlignedBox2d box;
  for (const auto& s : spheres) box.extend(s.uv);
  const Eigen::Vector2d origin = spheres[0].uv;
  const int c0 = static_cast<int>(std::floor(box.min().x() - reach)), c1 = static_cast<int>(std::ceil(box.max().x() + reach));
  const int r0 = static_cast<int>(std::floor(box.min().y() - reach)), r1 = static_cast<int>(std::ceil(box.max().y() + reach));
  if (c0 < 0 || r0 < 0 || c1 >= im.cols || r1 >= im.rows) return refined;

  WindowPixels window =
      window_pixels(im, spheres, origin, reach, radius_px, PixelAverages(shape, c0, r0, c1, r1), c0, r0, c1, r1);
  std::vector<Eigen::Vector2d>& offsets = window.offsets;
  std::vector<double>& values = window.values;
  std::vector<double>& shape_values = window.shape_values;
  const std::vector<bool>& clear = window.clear;
  const int pixels = static_cast<int>(values.size());

  // Parameters relative to the reference point keep the numbers small and well scaled. The
  // background starts from a linear fit to the pixels clear of the balls; each amplitude from the
  // highest pixel above it near that ball.
  std::vector<double> centre(2 * spheres.size()), disc(2 * spheres.size());
  double background[4] = {0, 0, 0, 0};
  const int terms = shape ? 4 : 3;
  Eigen::MatrixXd A(pixels, terms);
  Eigen::VectorXd b(pixels), weight(pixels);
  for (int k = 0; k < pixels; ++k) {
    const auto ku = static_cast<std::size_t>(k);
    A.row(k).head<3>() << 1.0, offsets[ku].x(), offsets[ku].y();
    if (shape) A(k, 3) = shape_values[ku];
    b(k) = values[ku];
    weight(k) = clear[ku] ? 1.0 : 0.0;
  }
  const Eigen::VectorXd start_background = (weight.asDiagonal() * A).colPivHouseholderQr().solve(weight.cwiseProduct(b));
  for (int t = 0; t < terms; ++t) background[t] = start_background(t);
  const Eigen::VectorXd above = b - A * start_background;
  for (int s = 0; s < n; ++s) {
    const auto su = static_cast<std::size_t>(s);
    const Eigen::Vector2d start = spheres[su].uv - origin;
    centre[2 * su] = start.x();
    centre[2 * su + 1] = start.y();
    double peak = 1e-6;
    for (int k = 0; k < pixels; ++k)
      if ((offsets[static_cast<std::size_t>(k)] - start).norm() < radius_px) peak = std::max(peak, above(k));
    disc[2 * su] = radius_px;
    disc[2 * su + 1] = peak / (2 * radius_px);
  }

  const double reference_background = background[0];
  auto* cost = new WindowCost(std::move(offsets), std::move(values), std::move(shape_values), n, o.subsamples, o.contrast_loss,
                              reference_background);
  ceres::Problem problem;
  problem.AddResidualBlock(cost, nullptr, {centre.data(), disc.data(), background});
  if (!shape) problem.SetManifold(background, new ceres::SubsetManifold(4, {3}));
  for (int s = 0; s < n; ++s) {
    problem.SetParameterLowerBound(disc.data(), 2 * s, 0.5 * radius_px);
    problem.SetParameterUpperBound(disc.data(), 2 * s, 2.0 * radius_px);
  }
  // Started within a pixel, the centre is settled to 1e-4 px after about six steps; the default
  // tolerances took 14 for nothing the pose could see.
  const ceres::Solver::Summary summary = solve_small_problem(problem, 25 + 5 * n, 1e-4);
  if (!summary.IsSolutionUsable()) return refined;
  for (int s = 0; s < n; ++s) {
    const auto su = static_cast<std::size_t>(s);
    const Eigen::Vector2d uv = origin + Eigen::Vector2d(centre[2 * su], centre[2 * su + 1]);
    const double radius = disc[2 * su], amplitude = disc[2 * su + 1];
    if (!(amplitude > 0) || !((uv - spheres[su].uv).norm() <= o.max_move_px)) continue;
    spheres[su].uv = uv;
    spheres[su].strength = 4 * M_PI / 3 * amplitude * radius * radius * radius;  // the ball's chords summed
    refined[su] = true;
  }
  return refined;
}

bool refine_by_profile_fit(const Image& im, double radius_px, SphereDetection& detection, const ProfileFitOptions& o,
                           const BackgroundShape& shape) {
  return refine_cluster_by_profile_fit(im, radius_px, std::span<SphereDetection>(&detection, 1), o, shape)[0];
}

}  // namespace ctk

#include "ctk/calib/ball_contrast.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>

namespace ctk {

namespace {

struct Line {
  double a0 = 0, slope = 0, slope_sigma = 0, residual_mad = 0;
};

Line fit_line(const std::vector<Eigen::Vector2d>& p) {
  const auto n = static_cast<Eigen::Index>(p.size());
  Eigen::MatrixXd A(n, 2);
  Eigen::VectorXd y(n);
  for (Eigen::Index i = 0; i < n; ++i) {
    A(i, 0) = 1.0;
    A(i, 1) = p[static_cast<std::size_t>(i)].x();
    y(i) = p[static_cast<std::size_t>(i)].y();
  }
  const Eigen::Vector2d x = A.colPivHouseholderQr().solve(y);
  const Eigen::VectorXd r = y - A * x;
  const double variance = n > 2 ? r.squaredNorm() / static_cast<double>(n - 2) : 0.0;
  const Eigen::Matrix2d C = variance * (A.transpose() * A).inverse();
  std::vector<double> absolute(r.data(), r.data() + n);
  for (double& v : absolute) v = std::abs(v);
  std::nth_element(absolute.begin(), absolute.begin() + n / 2, absolute.end());
  return {x(0), x(1), std::sqrt(std::max(0.0, C(1, 1))), absolute[static_cast<std::size_t>(n / 2)]};
}

}  // namespace

BallContrast fit_ball_contrast(const std::vector<Eigen::Vector2d>& pairs) {
  BallContrast c;
  std::vector<Eigen::Vector2d> kept;
  for (const Eigen::Vector2d& p : pairs)
    if (p.allFinite() && p.y() > 0) kept.push_back(p);
  if (kept.size() < 3) return c;
  Line line = fit_line(kept);
  std::vector<Eigen::Vector2d> inliers;
  for (const Eigen::Vector2d& p : kept)
    if (std::abs(p.y() - line.a0 - line.slope * p.x()) <= 4 * 1.4826 * line.residual_mad) inliers.push_back(p);
  if (inliers.size() >= 3) line = fit_line(inliers);
  c.balls = static_cast<int>(inliers.size());
  c.amplitude_at_zero = line.a0;
  if (line.a0 > 0) {
    c.hardening = -line.slope / line.a0;
    c.sigma = line.slope_sigma / line.a0;
  }
  return c;
}

}  // namespace ctk

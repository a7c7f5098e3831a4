#include "ctk/geom/helix.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace ctk {

Eigen::Vector3d Helix::at(double tau) const {
  const double a = rho_rad_per_mm * tau + phase_rad;
  return {radius_mm * std::cos(a), radius_mm * std::sin(a), tau};
}

Eigen::Vector3d Helix::tangent(double tau) const {
  const double a = rho_rad_per_mm * tau + phase_rad;
  return {-radius_mm * rho_rad_per_mm * std::sin(a), radius_mm * rho_rad_per_mm * std::cos(a), 1.0};
}

double Helix::nearest_tau(const Eigen::Vector3d& p) const {
  // Start from the axial coordinate, then Newton on |h(tau) - p|^2 (a few steps suffice).
  double tau = p.z();
  for (int i = 0; i < 20; ++i) {
    const Eigen::Vector3d d = at(tau) - p;
    const Eigen::Vector3d t = tangent(tau);
    const double a = rho_rad_per_mm * tau + phase_rad;
    const Eigen::Vector3d c(-radius_mm * rho_rad_per_mm * rho_rad_per_mm * std::cos(a),
                            -radius_mm * rho_rad_per_mm * rho_rad_per_mm * std::sin(a), 0.0);
    const double g = d.dot(t), h = t.dot(t) + d.dot(c);
    const double step = h > 0 ? g / h : g / t.dot(t);
    tau -= step;
    if (std::abs(step) < 1e-12) break;
  }
  return tau;
}

Holder Holder::on_helix(const Helix& helix, double sphere_diameter_mm, int count, double tau_begin, double tau_end) {
  Holder holder;
  holder.helix = helix;
  holder.sphere_diameter_mm = sphere_diameter_mm;
  for (int k = 0; k < count; ++k) {
    const double tau = count == 1 ? tau_begin : tau_begin + (tau_end - tau_begin) * k / (count - 1);
    holder.spheres_mm.push_back(helix.at(tau));
  }
  return holder;
}

Holder reference_helix_holder() {
  const Helix helix{28.0, 4 * M_PI / 80.0, 0.0};
  Holder holder = Holder::on_helix(helix, 2.0, 50, -40.0, 40.0);
  holder.wall = HolderWall{25.0, 28.0, Eigen::Vector2d(-59.0, 59.0)};
  return holder;
}

double HolderWall::chord_mm(const Eigen::Vector3d& point, const Eigen::Vector3d& direction) const {
  // Across the axis the line x(t) = point + t d (d of unit length) enters and leaves a circle of
  // radius r at the roots of |x_xy(t)|^2 = r^2; along the axis the ends cut the same line at
  // t = (end - point_w) / d_w. The wall is the outer circle's interval less the inner one's, each
  // clipped to the ends' interval.
  const Eigen::Vector3d d = direction.normalized();
  const double a = d.head<2>().squaredNorm();
  if (a < 1e-24) return 0;  // along the axis: never through the wall's cross-section twice
  const double b = point.head<2>().dot(d.head<2>()), c = point.head<2>().squaredNorm();
  double t_low = -std::numeric_limits<double>::infinity(), t_high = std::numeric_limits<double>::infinity();
  if (ends_mm && d.z() != 0) {
    const double t0 = (ends_mm->x() - point.z()) / d.z(), t1 = (ends_mm->y() - point.z()) / d.z();
    t_low = std::min(t0, t1);
    t_high = std::max(t0, t1);
  } else if (ends_mm && (point.z() < ends_mm->x() || point.z() > ends_mm->y())) {
    return 0;  // across the axis, beyond an end
  }
  auto inside = [&](double r) {
    const double discriminant = b * b - a * (c - r * r);
    if (discriminant <= 0) return 0.0;
    const double root = std::sqrt(discriminant);
    const double enter = std::max((-b - root) / a, t_low), leave = std::min((-b + root) / a, t_high);
    return std::max(0.0, leave - enter);
  };
  return inside(outer_radius_mm) - inside(inner_radius_mm);
}

double Holder::tau_min() const {
  double m = std::numeric_limits<double>::infinity();
  for (const auto& s : spheres_mm) m = std::min(m, s.z());
  return m;
}

double Holder::tau_max() const {
  double m = -std::numeric_limits<double>::infinity();
  for (const auto& s : spheres_mm) m = std::max(m, s.z());
  return m;
}

HelixPoint closest_point_on_projected_helix(const ProjectionMatrix& P, const Helix& helix, const Eigen::Vector2d& uv,
                                            double tau_begin, double tau_end) {
  auto distance2 = [&](double tau) { return (P.project(helix.at(tau)) - uv).squaredNorm(); };
  // Coarse scan finer than a quarter turn so each basin of the distance holds a sample.
  const double turn_mm = helix.rho_rad_per_mm != 0 ? 2 * M_PI / std::abs(helix.rho_rad_per_mm) : (tau_end - tau_begin);
  const int samples = std::max(16, static_cast<int>(std::ceil(64.0 * (tau_end - tau_begin) / turn_mm)));
  const double step = (tau_end - tau_begin) / samples;
  double best_tau = tau_begin, best = std::numeric_limits<double>::infinity();
  for (int i = 0; i <= samples; ++i) {
    const double tau = tau_begin + step * i;
    const double d = distance2(tau);
    if (d < best) best = d, best_tau = tau;
  }
  // Refine by Gauss-Newton on the residual r(tau) = proj(h(tau)) - uv, kept inside the bracket.
  double tau = best_tau;
  const double lo = std::max(tau_begin, best_tau - step), hi = std::min(tau_end, best_tau + step);
  for (int it = 0; it < 30; ++it) {
    Eigen::Matrix<double, 2, 3> J;
    const Eigen::Vector2d r = P.project(helix.at(tau), &J) - uv;
    const Eigen::Vector2d dr = J * helix.tangent(tau);
    const double denom = dr.squaredNorm();
    if (denom <= 0) break;
    const double next = std::clamp(tau - r.dot(dr) / denom, lo, hi);
    const bool converged = std::abs(next - tau) < 1e-10;
    tau = next;
    if (converged) break;
  }
  HelixPoint out;
  out.tau = tau;
  out.uv = P.project(helix.at(tau));
  out.distance_px = (out.uv - uv).norm();
  return out;
}

}  // namespace ctk

#include "ctk/calib/helix_fit.hpp"

#include <ceres/ceres.h>

#include <cmath>
#include <stdexcept>

namespace ctk {

namespace {

// The curve c + R (r cos(rho tau + phi), r sin(rho tau + phi), tau), R = R_v(b) R_u(a); c in the
// plane w = 0, which leaves no screw motion along the axis for tau and phi to trade.
template <typename T>
Eigen::Matrix<T, 3, 1> curve_point(const T* shape, const T* axis, const T& tau) {
  const T angle = shape[1] * tau + shape[2];
  const Eigen::Matrix<T, 3, 1> local(shape[0] * cos(angle), shape[0] * sin(angle), tau);
  const T ca = cos(axis[0]), sa = sin(axis[0]), cb = cos(axis[1]), sb = sin(axis[1]);
  // About u by a: (x, y cos a - z sin a, y sin a + z cos a); then about v by b.
  const Eigen::Matrix<T, 3, 1> u(local.x(), local.y() * ca - local.z() * sa, local.y() * sa + local.z() * ca);
  const Eigen::Matrix<T, 3, 1> uv(u.x() * cb + u.z() * sb, u.y(), -u.x() * sb + u.z() * cb);
  return uv + Eigen::Matrix<T, 3, 1>(axis[2], axis[3], T(0));
}

struct CentreOnCurve {
  Eigen::Vector3d centre;
  template <typename T>
  bool operator()(const T* shape, const T* axis, const T* tau, T* r) const {
    const Eigen::Matrix<T, 3, 1> p = curve_point(shape, axis, tau[0]);
    for (int i = 0; i < 3; ++i) r[i] = T(centre[i]) - p[i];
    return true;
  }
};

}  // namespace

Eigen::Vector3d HelixFit::at(double tau) const {
  const double shape[3] = {helix.radius_mm, helix.rho_rad_per_mm, helix.phase_rad};
  const double axis[4] = {axis_tilt_rad.x(), axis_tilt_rad.y(), axis_offset_mm.x(), axis_offset_mm.y()};
  return curve_point(shape, axis, tau);
}

HelixFit fit_helix(const std::vector<Eigen::Vector3d>& centres, const Helix& start) {
  if (centres.size() < 6)
    throw std::invalid_argument("fit_helix: expected at least 6 centres, got " + std::to_string(centres.size()));
  double shape[3] = {start.radius_mm, start.rho_rad_per_mm, start.phase_rad};
  double axis[4] = {0, 0, 0, 0};
  std::vector<double> tau;
  tau.reserve(centres.size());
  for (const Eigen::Vector3d& c : centres) tau.push_back(start.nearest_tau(c));
  ceres::Problem problem;
  for (std::size_t k = 0; k < centres.size(); ++k)
    problem.AddResidualBlock(new ceres::AutoDiffCostFunction<CentreOnCurve, 3, 3, 4, 1>(new CentreOnCurve{centres[k]}), nullptr,
                             shape, axis, &tau[k]);
  ceres::Solver::Options options;
  options.linear_solver_type = ceres::DENSE_SCHUR;
  options.max_num_iterations = 100;
  options.function_tolerance = 1e-14;
  options.logging_type = ceres::SILENT;
  ceres::Solver::Summary summary;
  ceres::Solve(options, &problem, &summary);

  HelixFit fit;
  fit.converged = summary.IsSolutionUsable();
  fit.helix = {shape[0], shape[1], shape[2]};
  fit.axis_tilt_rad = {axis[0], axis[1]};
  fit.axis_offset_mm = {axis[2], axis[3]};
  fit.tau_mm = tau;
  double sq = 0;
  for (std::size_t k = 0; k < centres.size(); ++k) {
    fit.deviation_mm.push_back(centres[k] - fit.at(tau[k]));
    sq += fit.deviation_mm.back().squaredNorm();
  }
  fit.rms_deviation_mm = std::sqrt(sq / static_cast<double>(centres.size()));
  return fit;
}

}  // namespace ctk

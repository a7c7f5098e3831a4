#include "ctk/geom/detector.hpp"

#include <Eigen/Geometry>
#include <stdexcept>

namespace ctk {

bool Detector::contains(const Eigen::Vector2d& uv, double margin_px) const {
  return uv.x() >= -0.5 + margin_px && uv.x() <= cols - 0.5 - margin_px && uv.y() >= -0.5 + margin_px &&
         uv.y() <= rows - 0.5 - margin_px;
}

Intrinsics Intrinsics::from_setup(double sdd_mm, const Detector& detector, const Eigen::Vector2d& principal_point_px) {
  return {sdd_mm / detector.pitch_u_mm, sdd_mm / detector.pitch_v_mm, 0.0, principal_point_px.x(), principal_point_px.y()};
}

Eigen::Matrix3d Intrinsics::K() const {
  Eigen::Matrix3d K;
  K << fu_px, skew_px, u0_px, 0, fv_px, v0_px, 0, 0, 1;
  return K;
}

Intrinsics Intrinsics::from_K(const Eigen::Matrix3d& K) {
  if (std::abs(K(1, 0)) + std::abs(K(2, 0)) + std::abs(K(2, 1)) > 1e-9 * K.norm() || std::abs(K(2, 2) - 1) > 1e-9)
    throw std::invalid_argument("Intrinsics::from_K: K must be upper triangular with K(2,2) = 1");
  return {K(0, 0), K(1, 1), K(0, 1), K(0, 2), K(1, 2)};
}

Eigen::Matrix3d tilted_detector_matrix(const Intrinsics& nominal, double sdd_mm, const Detector& detector,
                                       double tilt_about_u_rad, double tilt_about_v_rad) {
  // Plane through c0 = (0, 0, f) with axes e_u, e_v and normal n, all rotated by the tilt.
  // Ray point X: intersection at lambda X with lambda = (n.c0) / (n.X); in-plane offset
  // p = lambda X - c0; u = u0 + e_u.p / pu. Multiplying by n.X makes every row linear in X.
  const Eigen::Matrix3d R = (Eigen::AngleAxisd(tilt_about_u_rad, Eigen::Vector3d::UnitX()) *
                             Eigen::AngleAxisd(tilt_about_v_rad, Eigen::Vector3d::UnitY()))
                                .toRotationMatrix();
  const Eigen::Vector3d eu = R.col(0), ev = R.col(1), n = R.col(2);
  const double f = sdd_mm;
  Eigen::Matrix3d M;
  M.row(0) = (f * n.z() / detector.pitch_u_mm) * eu.transpose() - (f * eu.z() / detector.pitch_u_mm) * n.transpose() +
             nominal.u0_px * n.transpose();
  M.row(1) = (f * n.z() / detector.pitch_v_mm) * ev.transpose() - (f * ev.z() / detector.pitch_v_mm) * n.transpose() +
             nominal.v0_px * n.transpose();
  M.row(2) = n.transpose();
  return M;
}

Eigen::Matrix3d detector_matrix_for_source_at(const Eigen::Matrix3d& M, double sdd_mm, const Eigen::Vector3d& delta) {
  // A point X (camera frame) seen from the source at delta meets the plane n.Y = d at
  // Y = delta + lambda (X - delta), lambda = (d - n.delta) / n.(X - delta). Pixels are affine in
  // Y on the plane, (M Y) / d; clearing the denominator leaves a matrix acting on X - delta.
  const Eigen::Vector3d n = M.row(2).transpose();
  const double d = n.z() * sdd_mm;
  return (d - n.dot(delta)) * M + (M * delta) * n.transpose();
}

Eigen::Vector2d RadialDistortion::measured_from_ideal(const Eigen::Vector2d& x) const {
  const Eigen::Vector2d r = x - centre_px;
  return x + k1_per_px2 * r.squaredNorm() * r;
}

Eigen::Vector2d RadialDistortion::ideal_from_measured(const Eigen::Vector2d& m) const {
  Eigen::Vector2d x = m;
  for (int i = 0; i < 50; ++i) {
    const Eigen::Vector2d r = x - centre_px;
    const Eigen::Vector2d next = m - k1_per_px2 * r.squaredNorm() * r;
    const bool converged = (next - x).squaredNorm() < 1e-24;
    x = next;
    if (converged) break;
  }
  return x;
}

}  // namespace ctk

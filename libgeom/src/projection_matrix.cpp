#include "ctk/geom/projection_matrix.hpp"

#include <Eigen/LU>
#include <Eigen/QR>
#include <stdexcept>

namespace ctk {

ProjectionMatrix::ProjectionMatrix() : P_(Matrix34d::Zero()) { P_.leftCols<3>().setIdentity(); }

ProjectionMatrix::ProjectionMatrix(const Matrix34d& P) {
  const Eigen::Matrix3d M = P.leftCols<3>();
  const double scale = P.block<1, 3>(2, 0).norm();
  if (!(scale > 0) || !std::isfinite(scale) || std::abs(M.determinant()) <= 1e-12 * std::pow(M.norm(), 3))
    throw std::invalid_argument("projection matrix: the left 3x3 block is singular or not finite");
  P_ = P / scale;
}

ProjectionMatrix ProjectionMatrix::compose(const Intrinsics& K, const Rigid& T) { return compose(K.K(), T); }

ProjectionMatrix ProjectionMatrix::compose(const Eigen::Matrix3d& K, const Rigid& T) {
  Matrix34d Rt;
  Rt.leftCols<3>() = T.linear();
  Rt.col(3) = T.translation();
  return ProjectionMatrix(K * Rt);
}

ProjectionMatrix::Decomposition ProjectionMatrix::decompose() const {
  // RQ of M through QR of its inverse: M^-1 = Q U  =>  M = U^-1 Q^T, U^-1 upper triangular.
  const Eigen::Matrix3d M = P_.leftCols<3>();
  Eigen::HouseholderQR<Eigen::Matrix3d> qr(M.inverse());
  Eigen::Matrix3d Q = qr.householderQ();
  Eigen::Matrix3d U = qr.matrixQR().triangularView<Eigen::Upper>();
  // Make U's diagonal positive: Q U = (Q D)(D U) with D = diag(sign).
  for (int i = 0; i < 3; ++i) {
    if (U(i, i) < 0) {
      U.row(i) *= -1;
      Q.col(i) *= -1;
    }
  }
  Eigen::Matrix3d K = U.inverse();
  Eigen::Matrix3d R = Q.transpose();
  if (R.determinant() < 0) {  // mirrored detector: carry the reflection in K's first column
    R.row(0) *= -1;
    K.col(0) *= -1;
  }
  // Row 3 of M is K(2,2) * r3 with |r3| = 1 and |m3| = 1 after normalisation, so K(2,2) = 1.
  const Eigen::Vector3d t = K.triangularView<Eigen::Upper>().solve(Eigen::Vector3d(P_.col(3)));
  K(1, 0) = K(2, 0) = K(2, 1) = 0;
  K(2, 2) = 1;
  Decomposition d;
  d.intrinsics = Intrinsics::from_K(K);
  d.T_camera_frame = make_rigid(R, t);
  return d;
}

Eigen::Vector3d ProjectionMatrix::source_position() const { return -P_.leftCols<3>().partialPivLu().solve(P_.col(3)); }

Eigen::Vector3d ProjectionMatrix::principal_ray() const { return P_.block<1, 3>(2, 0).transpose().normalized(); }

Eigen::Vector3d ProjectionMatrix::ray_direction(const Eigen::Vector2d& uv) const {
  Eigen::Vector3d d = P_.leftCols<3>().partialPivLu().solve(Eigen::Vector3d(uv.x(), uv.y(), 1.0));
  // Points C + s d have depth s * (m3 . d): make it positive.
  if (P_.block<1, 3>(2, 0).dot(d) < 0) d = -d;
  return d.normalized();
}

Eigen::Vector2d ProjectionMatrix::project(const Eigen::Vector3d& X) const {
  const Eigen::Vector3d p = P_.leftCols<3>() * X + P_.col(3);
  return {p.x() / p.z(), p.y() / p.z()};
}

Eigen::Vector2d ProjectionMatrix::project(const Eigen::Vector3d& X, Eigen::Matrix<double, 2, 3>* jacobian) const {
  const Eigen::Vector3d p = P_.leftCols<3>() * X + P_.col(3);
  const double w = 1.0 / p.z();
  if (jacobian) {
    jacobian->row(0) = (P_.block<1, 3>(0, 0) - p.x() * w * P_.block<1, 3>(2, 0)) * w;
    jacobian->row(1) = (P_.block<1, 3>(1, 0) - p.y() * w * P_.block<1, 3>(2, 0)) * w;
  }
  return {p.x() * w, p.y() * w};
}

double ProjectionMatrix::depth(const Eigen::Vector3d& X) const { return P_.block<1, 3>(2, 0).dot(X) + P_(2, 3); }

ProjectionMatrix ProjectionMatrix::oriented_towards(const Eigen::Vector3d& point_in_front) const {
  ProjectionMatrix out = *this;
  if (depth(point_in_front) < 0) out.P_ = -out.P_;
  return out;
}

ProjectionMatrix ProjectionMatrix::then(const Rigid& T) const { return ProjectionMatrix(Matrix34d(P_ * T.matrix())); }

std::array<double, 12> ProjectionMatrix::row_major() const {
  std::array<double, 12> p{};
  for (Eigen::Index r = 0; r < 3; ++r)
    for (Eigen::Index c = 0; c < 4; ++c) p[static_cast<std::size_t>(4 * r + c)] = P_(r, c);
  return p;
}

ProjectionMatrix ProjectionMatrix::from_row_major(const std::array<double, 12>& p) {
  Matrix34d P;
  for (Eigen::Index r = 0; r < 3; ++r)
    for (Eigen::Index c = 0; c < 4; ++c) P(r, c) = p[static_cast<std::size_t>(4 * r + c)];
  return ProjectionMatrix(P);
}

double max_abs_difference(const ProjectionMatrix& a, const ProjectionMatrix& b) {
  return (a.matrix() - b.matrix()).cwiseAbs().maxCoeff();
}

}  // namespace ctk

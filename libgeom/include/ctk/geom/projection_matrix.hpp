#pragma once
// The per-view 3x4 projection matrix of the contract: P = K [R | t] maps homogeneous holder-frame
// millimetres to detector pixels, (u, v) = (p0 / p2, p1 / p2). Stored normalised: the third row's
// first three entries have unit norm, so p2 is the depth in mm (positive in front of the source).
#include <Eigen/Core>
#include <array>

#include "ctk/geom/detector.hpp"
#include "ctk/geom/rigid.hpp"

namespace ctk {

using Matrix34d = Eigen::Matrix<double, 3, 4>;

class ProjectionMatrix {
 public:
  ProjectionMatrix();  // K = I, R = I, t = 0
  /// Normalises by a positive factor (keeps the caller's sign: depth must be positive in front).
  /// Throws std::invalid_argument when the left 3x3 block is singular.
  explicit ProjectionMatrix(const Matrix34d& P);

  static ProjectionMatrix compose(const Intrinsics& K, const Rigid& T_camera_frame);
  /// For a general (e.g. tilted-detector) 3x3 matrix whose third row is the detector normal.
  static ProjectionMatrix compose(const Eigen::Matrix3d& K, const Rigid& T_camera_frame);

  struct Decomposition {
    Intrinsics intrinsics;  // fu may be negative for a mirrored (left-handed) detector
    Rigid T_camera_frame;   // proper rotation
  };
  /// RQ decomposition P = K [R | t] with K upper triangular, K(1,1) > 0, K(2,2) = 1, det R = +1.
  Decomposition decompose() const;

  Eigen::Vector3d source_position() const;
  /// Unit vector from the source along the principal ray, in the frame P maps from.
  Eigen::Vector3d principal_ray() const;
  /// Unit direction of the ray through pixel (u, v), pointing away from the source.
  Eigen::Vector3d ray_direction(const Eigen::Vector2d& uv) const;

  Eigen::Vector2d project(const Eigen::Vector3d& X) const;
  /// Also returns d(u, v) / dX.
  Eigen::Vector2d project(const Eigen::Vector3d& X, Eigen::Matrix<double, 2, 3>* jacobian) const;
  double depth(const Eigen::Vector3d& X) const;

  /// Flips the overall sign if needed so that `point_in_front` has positive depth.
  ProjectionMatrix oriented_towards(const Eigen::Vector3d& point_in_front) const;
  /// Same matrix for points given in another frame: P' = P * T_frame_other.
  ProjectionMatrix then(const Rigid& T_frame_other) const;

  const Matrix34d& matrix() const { return P_; }
  std::array<double, 12> row_major() const;
  static ProjectionMatrix from_row_major(const std::array<double, 12>& p);

 private:
  Matrix34d P_;
};

/// Projects X with a row-major 3x4 P; templated for automatic differentiation (Ceres Jets).
template <typename T>
inline void project_point(const T* P, const T* X, T* uv) {
  const T p0 = P[0] * X[0] + P[1] * X[1] + P[2] * X[2] + P[3];
  const T p1 = P[4] * X[0] + P[5] * X[1] + P[6] * X[2] + P[7];
  const T p2 = P[8] * X[0] + P[9] * X[1] + P[10] * X[2] + P[11];
  uv[0] = p0 / p2;
  uv[1] = p1 / p2;
}

/// Largest |difference| over the entries of two normalised matrices (a test helper users can call).
double max_abs_difference(const ProjectionMatrix& a, const ProjectionMatrix& b);

}  // namespace ctk

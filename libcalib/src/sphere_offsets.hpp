#pragma once
// What the diagnosis and its report both ask of the spheres' offsets (sphere_positions).
#include <Eigen/Dense>
#include <algorithm>
#include <cstddef>

#include "ctk/calib/scan_model.hpp"

namespace ctk {

// Whether every sphere's centre is free: the holder's geometry as a whole.
inline bool all_spheres_free(const EffectParameters& p) {
  return !p.free_spheres.empty() && std::find(p.free_spheres.begin(), p.free_spheres.end(), false) == p.free_spheres.end();
}

// Whether sphere k's offset x differs from zero beyond chance (chi-square, 3 dof, p < 0.001),
// from the covariance C of all sphere offsets (pseudo-inverse: the gauge leaves directions
// unfixed); without a covariance, beyond 0.03 mm. `sigma` gets its standard deviations.
inline bool sphere_offset_significant(const Eigen::Vector3d& x, const Eigen::MatrixXd& C, std::size_t k, Eigen::Vector3d* sigma) {
  if (C.rows() < static_cast<Eigen::Index>(3 * (k + 1))) return x.norm() > 0.03;
  const Eigen::Matrix3d Ck = C.block(static_cast<Eigen::Index>(3 * k), static_cast<Eigen::Index>(3 * k), 3, 3);
  if (sigma) *sigma = Ck.diagonal().cwiseMax(0.0).cwiseSqrt();
  const Eigen::Matrix3d inv = Ck.completeOrthogonalDecomposition().pseudoInverse();
  return x.dot(inv * x) > 16.27;
}

}  // namespace ctk

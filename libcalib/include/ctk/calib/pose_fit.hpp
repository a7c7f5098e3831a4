#pragma once
// The pose of the holder in one view from matched sphere centres: Ceres minimises the
// reprojection error through the (fixed) detector matrix, rotation as a unit quaternion on its
// manifold, automatic derivatives, a robust (Cauchy) loss against the odd wrong match.
#include <Eigen/Core>
#include <vector>

#include "ctk/geom/rigid.hpp"

namespace ctk {

struct PoseFit {
  Rigid T_camera_holder = Rigid::Identity();
  std::vector<double> residual_px;  // per point, after the fit
  double rms_px = 0;
  double translation_sigma_mm[3] = {0, 0, 0};  // camera x, y, z (z: along the beam, weakly seen)
  double rotation_sigma_deg = 0;               // largest axis
  bool converged = false;
};

/// `K` maps camera-frame points to homogeneous pixels (K or a tilted-detector matrix).
/// Uncertainties scale the covariance by the residual variance.
PoseFit fit_pose(const Eigen::Matrix3d& K, const Rigid& initial, const std::vector<Eigen::Vector3d>& points_holder,
                 const std::vector<Eigen::Vector2d>& observed_px, double robust_scale_px = 1.0);

}  // namespace ctk

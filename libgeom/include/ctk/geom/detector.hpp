#pragma once
// The flat-panel detector and the intrinsic matrix K of the contract (scan-format.md):
// K = [[f/pu, skew, u0], [0, f/pv, v0], [0, 0, 1]], f = source-to-detector distance (mm).
#include <Eigen/Core>

namespace ctk {

struct Detector {
  int cols = 0;
  int rows = 0;
  double pitch_u_mm = 0;  // column direction
  double pitch_v_mm = 0;  // row direction

  /// Pixel coordinates of the detector's geometric centre ((cols-1)/2, (rows-1)/2).
  Eigen::Vector2d centre_px() const { return {0.5 * (cols - 1), 0.5 * (rows - 1)}; }
  bool contains(const Eigen::Vector2d& uv, double margin_px = 0) const;
};

struct Intrinsics {
  double fu_px = 0;  // f / pu
  double fv_px = 0;  // f / pv
  double skew_px = 0;
  double u0_px = 0;
  double v0_px = 0;

  static Intrinsics from_setup(double sdd_mm, const Detector& detector, const Eigen::Vector2d& principal_point_px);
  Eigen::Matrix3d K() const;
  /// K must be upper triangular with K(2,2) = 1 (as a decomposition returns it).
  static Intrinsics from_K(const Eigen::Matrix3d& K);
};

/// The 3x3 matrix taking camera-frame points to homogeneous pixels for a detector whose plane is
/// rotated by `tilt_about_u_rad` (about the detector's u axis) then `tilt_about_v_rad` about the
/// point where the principal ray meets it. It is a general (not upper triangular) matrix whose
/// third row is the plane's unit normal, so p2 stays a depth in mm. Zero tilt gives K().
Eigen::Matrix3d tilted_detector_matrix(const Intrinsics& nominal, double sdd_mm, const Detector& detector,
                                       double tilt_about_u_rad, double tilt_about_v_rad);

/// The focal spot's offset at `view` (camera frame, mm) under a linear drift from view 0 of
/// (drift_x, drift_y) mm per 100 views in camera x and y, the detector staying put: the one drift
/// model of scan files, calibration, diagnosis and simulation. Templated for automatic derivatives.
template <typename T>
Eigen::Matrix<T, 3, 1> drifted_focal_spot_mm(const T& drift_x, const T& drift_y, double view) {
  const T per_view(view / 100.0);
  return Eigen::Matrix<T, 3, 1>(drift_x * per_view, drift_y * per_view, T(0.0));
}

/// The detector matrix seen from a focal spot displaced by `source_offset_mm` (camera frame) while
/// the detector stays put: P = M' [I | -offset] [R | t]. `M` is a detector matrix whose third
/// row is the plane's unit normal n (K or a tilted one) and the plane passes through (0, 0, sdd).
Eigen::Matrix3d detector_matrix_for_source_at(const Eigen::Matrix3d& M, double sdd_mm, const Eigen::Vector3d& source_offset_mm);

/// Radial distortion of the detector about a centre, as the diagnosis contract names it: a point
/// whose ideal (pinhole) projection is x is measured at x + k1 |x - c|^2 (x - c).
struct RadialDistortion {
  double k1_per_px2 = 0;
  Eigen::Vector2d centre_px{0, 0};

  Eigen::Vector2d measured_from_ideal(const Eigen::Vector2d& ideal_px) const;
  /// The inverse, by fixed-point iteration (converges while |3 k1 r^2| < 1 over the detector).
  Eigen::Vector2d ideal_from_measured(const Eigen::Vector2d& measured_px) const;
};

}  // namespace ctk

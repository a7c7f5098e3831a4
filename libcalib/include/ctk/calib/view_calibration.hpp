#pragma once
// One view, from its image and a first-guess pose to a calibrated projection matrix or a
// rejection with its reason: detect, predict, match (shift + optimal assignment), fit the pose,
// then predict again from the fitted pose, rematch tightly and refit.
#include <optional>
#include <string>
#include <vector>

#include "ctk/calib/sphere_detection.hpp"
#include "ctk/geom/geometry_file.hpp"
#include "ctk/geom/helix.hpp"

namespace ctk {

/// The largest rate at which a ball's contrast may fall per unit of background line integral;
/// beyond it the chord scaling, a first-order model, would turn contrast negative within reach.
inline constexpr double kMostContrastLoss = 2.0;

struct CalibrationOptions {
  int min_spheres = 6;                     // fewer matched spheres: rejected
  double max_rms_px = 0.5;                 // larger reprojection RMS: rejected
  double search_px = 40;                   // how far the first guess may put the pattern (5 mm / 3 deg here)
  double robust_px = 1.0;                  // Cauchy scale of the pose fit
  double max_first_guess_error_deg = 6.0;  // a fitted pose turned further from the guess is refused
  double contrast_loss = 0;                // the balls' contrast lost per unit background line integral (contrast_loss.hpp)
  void validate() const;                   // std::invalid_argument naming the field
};

struct ViewCalibration {
  ViewStatus status = ViewStatus::rejected;
  std::string reason;
  std::optional<ProjectionMatrix> P;
  std::optional<Rigid> T_camera_holder;
  double rms_px = 0;
  int spheres_used = 0;
  int detections = 0;
  double radius_px = 0;                        // projected sphere radius the detection looked for
  double translation_sigma_mm[3] = {0, 0, 0};  // camera x, y, z (z along the beam)
  double rotation_sigma_deg = 0;
  std::vector<Eigen::Vector2d> detected_px, fitted_px;  // the used pairs, for pictures
  std::vector<int> spheres;                             // their sphere indices
  /// Matched spheres left out of the fit as outliers (a sample's edge pulling one view's centre,
  /// or a sphere that is not where the holder's list says: the diagnosis tells them apart).
  std::vector<int> outlier_spheres;
  std::vector<Eigen::Vector2d> outlier_detected_px;
  /// The pose fit converged on enough spheres, so the residual alone decides the status (against
  /// the scan's limit, residual_limit_px).
  bool residual_decides = false;
};

/// Accepts a view whose pose fit converged when its residual is within `limit_px`, else rejects
/// it saying so.
void judge_residual(ViewCalibration& view, double limit_px);

/// The residual a view of a scan may have: `max_rms_px`, or twice the median over the scan's
/// converged fits when that is higher. A holder whose every sphere is a little off (a printed
/// one), or a detector effect the model lacks, raises every view's residual alike; a view is then
/// rejected only when its residual stands out from the scan's own.
double residual_limit_px(const std::vector<ViewCalibration>& views, const CalibrationOptions& options);

/// `K`: the scan's detector matrix; `initial`: first-guess T_camera_holder (robot FK);
/// `distortion`: the detector's declared radial distortion (centres are undistorted before the
/// fit, so P stays the pinhole matrix of the contract; detected_px are then ideal positions).
ViewCalibration calibrate_view(const Image& line_integrals, const Eigen::Matrix3d& K, const Rigid& initial, const Holder& holder,
                               const Detector& detector, const CalibrationOptions& options,
                               const std::optional<RadialDistortion>& distortion = std::nullopt);

}  // namespace ctk

#pragma once
// Each view's pose from its spheres and the robot's report together. The image fixes a pose
// across the beam to micrometres, but its tilts only to about a hundredth of a degree and its
// depth to a tenth of a millimetre; a robot repeats its pose about as well once its base and the
// holder's mount are where they really are. So the base and mount offsets are fitted over the
// whole scan (a bundle adjustment with every view's pose), the robot's repeatability is measured
// from how far the image poses scatter about that model (less the image's own share of the
// scatter), and each pose is then fitted to its spheres and that prior, each weighted by its
// noise. A robot worse than the model (unmodelled kinematics, a sagging holder) shows a larger
// scatter, which weakens its prior: the image always keeps its say.
#include <string>
#include <vector>

#include "ctk/calib/scan_calibration.hpp"
#include "ctk/calib/scan_model.hpp"
#include "ctk/geom/scan.hpp"

namespace ctk {

struct RobotPriorOptions {
  int min_views = 12;             // fewer calibrated robot views: no prior (the model has 12 offsets)
  double start_sigma_mm = 0.1;    // repeatability the first fit assumes (3-D RMS) ...
  double start_sigma_deg = 0.02;  // ... before it is measured
  void validate() const;          // std::invalid_argument naming the field
};

struct RobotPriorFit {
  bool applied = false;
  std::string reason;                  // why not, when not applied
  int views = 0;                       // views combined with the prior
  double sigma_mm = 0, sigma_deg = 0;  // the repeatability measured on the scan (3-D RMS)
  EffectParameters model;              // the fitted base and mount offsets
  /// Views whose image pose and the robot's disagree beyond both noises (p < 0.001): left out of
  /// the model's fit; their poses are still combined (the image's noise grows with its residual).
  std::vector<int> inconsistent_views;
  /// Median over the views of the rotation's uncertainty (largest axis) from the image alone and
  /// with the prior.
  double image_rotation_sigma_deg = 0, combined_rotation_sigma_deg = 0;
};

/// Replaces the pose, P, residuals and uncertainties of every ok view of `c` that has joints by
/// the combination of its image and the robot's prior. Leaves `c` as it is (and says why) when
/// the scan's poses do not come from a robot or too few views were calibrated.
RobotPriorFit combine_with_robot(const ScanDescription& scan, ScanCalibration& c, const RobotPriorOptions& options = {});

}  // namespace ctk

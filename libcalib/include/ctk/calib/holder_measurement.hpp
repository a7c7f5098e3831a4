#pragma once
// Holder self-calibration: every sphere's centre measured from one scan of the holder, jointly
// with every view's pose (a bundle adjustment over the whole scan), after the diagnosis has found
// what the robot and the detector add. The holder frame stays the one the declared centres
// define: the measured centres neither move, turn nor scale the declared list as a whole (the
// scan model's sphere gauge), so a pose calibrated with the measured holder lands where one
// calibrated with the declared holder would, less the holder's own error. Each centre comes
// with its uncertainty (the bundle's marginal covariance, scaled by the fit's variance factor:
// the noise measured on the declared holder carries the holder's own error; and by how far the
// even and the odd views' measurements differ beyond what they state), and a helix is fitted to
// the measured centres. The result is a ctk-holder/1 file that later scans declare.
#include <Eigen/Core>
#include <functional>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "ctk/calib/diagnosis_run.hpp"
#include "ctk/calib/helix_fit.hpp"

namespace ctk {

struct HolderMeasurementOptions {
  DiagnosisRunOptions diagnosis;
  int min_views = 60;     // a scan of the holder from fewer well-spread views leaves centres poorly fixed
  void validate() const;  // std::invalid_argument naming the field
};

struct HolderMeasurement {
  DiagnosisRun diagnosis;                 // what the robot and the detector add, found first and fitted beside the centres
  std::vector<Effect> fitted_with;        // the effects fitted jointly with the centres
  Holder declared, measured;              // measured: the declared holder with the measured centres
  std::vector<Eigen::Vector3d> sigma_mm;  // each measured centre's standard deviation per axis
  std::vector<int> views_per_sphere;      // views in which each sphere was matched
  double rms_px_declared = 0;             // image RMS per sphere with the declared holder and setup (the diagnosis' baseline)
  double rms_px_measured = 0;             // with every centre measured
  double variance_factor = 1;             // chi-square per degree of freedom of the joint fit (the covariance scaled by it)
  /// RMS of the even and the odd views' centres' difference in units of its stated deviation: above
  /// 1, the uncertainties are scaled by it (errors the detection noise does not explain).
  double halves_factor = 0;
  HelixFit helix;  // the helix through the measured centres

  /// The ctk-holder/1 file: the declared holder's helix, diameter and wall, the measured centres,
  /// and a `measurement` block (source scan, uncertainties, helix fit, figures).
  nlohmann::json holder_file(const std::string& scan_name) const;
  /// What was measured, a few lines.
  std::string brief() const;
};

/// Throws InputError naming the scan (no holder) or the geometry (fewer than `min_views`
/// calibrated views).
HolderMeasurement run_holder_measurement(const ScanDescription& scan, const Geometry& geometry,
                                         const HolderMeasurementOptions& options,
                                         const std::function<void(int, int)>& progress = {},
                                         const std::function<void(const std::string&)>& log = {});

}  // namespace ctk

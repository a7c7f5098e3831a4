#pragma once
// The calibration workflow on a whole scan, as `ctk calibrate` and Python's `ctk.calibrate` run
// it: every view from its own image (calibrate_scan); a holder wall the scan does not declare
// measured from the images and the views it cost calibrated again with it; the spheres' contrast
// loss over their background measured on a sample of views and applied; the poses combined
// with the robot's prior unless asked not to. Returns the calibration and its report; files
// (geometry, journal, pictures) are the caller's.
#include <filesystem>
#include <functional>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>

#include "ctk/calib/contrast_loss.hpp"
#include "ctk/calib/holder_wall.hpp"
#include "ctk/calib/robot_prior.hpp"
#include "ctk/calib/scan_calibration.hpp"

namespace ctk {

struct CalibrationRunOptions {
  CalibrationOptions calibration;
  bool image_only = false;                           // poses from the images alone, no robot prior
  void validate() const { calibration.validate(); }  // std::invalid_argument naming the field
};

struct CalibrationRun {
  ScanCalibration calibration;  // left_undone > 0: stopped on request, nothing after the views was done
  std::optional<HolderWall> declared_wall;
  std::optional<WallMeasurement> wall;                   // measured, when the scan does not declare it
  std::optional<ContrastLossMeasurement> contrast_loss;  // measured on a sample of views before the batch
  bool has_holder = false;
  RobotPriorFit prior;
  CalibrationOptions options;  // as the views were calibrated (the measured contrast loss in it when used)

  /// ctk-calibration-report/1: summary, options, per-view table, holder wall, robot prior (the
  /// caller adds the file names and pictures).
  nlohmann::json report() const;
  /// The report's summary alone: views ok / rejected / skipped, median RMS and pose
  /// uncertainties, time and views/s.
  nlohmann::json summary() const;
  /// "calibrated N of M views (...) in s (views/s); median reprojection RMS ...".
  std::string brief() const;
  /// What was done about the holder's wall and the robot's prior, a line each.
  std::string wall_and_prior() const;
  /// The command to run next on the scan `scan_file` calibrated into `geometry_file`: the
  /// diagnosis for a scan with a holder (its report beside the geometry), else the reconstruction.
  std::string next_command(const std::filesystem::path& scan_file, const std::filesystem::path& geometry_file) const;
};

/// `progress(done, total)` after each view; `control` takes over an earlier run's views, journals
/// each finished one and may stop the batch. Over several `ranks` (every rank calling with the
/// same arguments, `control` null) the views are dealt to the ranks and every rank returns the
/// whole run (the holder's wall and the robot's prior are fitted on each, to the same numbers).
CalibrationRun run_calibration(const ScanDescription& scan, const CalibrationRunOptions& options,
                               const std::function<void(int, int)>& progress = {}, const BatchControl* control = nullptr,
                               const Communicator& ranks = single_process());

}  // namespace ctk

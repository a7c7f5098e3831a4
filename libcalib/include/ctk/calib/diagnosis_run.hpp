#pragma once
// The diagnosis workflow on a calibrated scan, as `ctk diagnose` and Python's `ctk.diagnose` run
// it: the detections behind the calibration found again from its poses, the robot's repeatability
// measured on the scan unless stated, a holder wall the scan does not declare measured in the
// images and modelled as if declared, the spheres' contrast loss over their background measured
// as ctk calibrate measures it, the bundle adjustment with held-out acceptance; returns the
// diagnosis, its report and the corrected scan. Files and pictures are the caller's.
#include <filesystem>
#include <functional>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>

#include "ctk/calib/contrast_loss.hpp"
#include "ctk/calib/diagnosis.hpp"
#include "ctk/calib/holder_wall.hpp"
#include "ctk/calib/scan_calibration.hpp"

namespace ctk {

struct DiagnosisRunOptions {
  DiagnosisOptions diagnosis;
  CalibrationOptions calibration;
  std::optional<double> repeatability_mm, repeatability_deg;  // absent: measured on the scan
  void validate() const;                                      // std::invalid_argument naming the field, its own and its parts'
};

struct DiagnosisRun {
  ScanObservations observations;
  Diagnosis diagnosis;
  ScanDescription corrected;              // the scan with the accepted effects (and a measured wall) declared
  std::string repeatability;              // how the robot's repeatability was set, one line
  std::optional<WallMeasurement> wall;    // measured, when the scan does not declare it (or its ends)
  bool wall_declared = false;             // the scan declared the wall's radii
  ContrastLossMeasurement contrast_loss;  // measured on a sample of views as ctk calibrate measures it
  /// ctk-diagnosis/1 (the caller adds file names and pictures).
  nlohmann::json report() const;
  /// The baseline and each accepted effect, a line each.
  std::string brief() const;
  /// The command to run next on the scan `scan_file` and its calibration `geometry_file`: measuring
  /// the holder when every sphere is off, calibrating `corrected_file` (the corrected scan, where
  /// written) again when an effect was accepted, else the reconstruction.
  std::string next_command(const std::filesystem::path& scan_file, const std::filesystem::path& geometry_file,
                           const std::filesystem::path& corrected_file) const;
};

/// Throws InputError naming the scan (no holder) or the geometry (fewer than 10 calibrated views).
DiagnosisRun run_diagnosis(const ScanDescription& scan, const Geometry& geometry, const DiagnosisRunOptions& options,
                           const std::function<void(int, int)>& progress = {},
                           const std::function<void(const std::string&)>& log = {});

}  // namespace ctk

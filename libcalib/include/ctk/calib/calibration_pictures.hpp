#pragma once
// The pictures of a calibration report: reprojection RMS per view against the rejection
// threshold; one view's image with the detected centres, the fitted projections and the
// residuals magnified; the view directions (source as seen from the holder) on an equal-area map
// of the sphere, so coverage and the places where views fail can be judged at a glance.
#include <filesystem>
#include <string>
#include <vector>

#include "ctk/calib/scan_calibration.hpp"
#include "ctk/calib/view_calibration.hpp"
#include "ctk/geom/scan.hpp"

namespace ctk {

void write_residual_per_view_png(const std::vector<ViewCalibration>& views, double threshold_px,
                                 const std::filesystem::path& png);

/// `line_integrals`: the view's image. Residual vectors are drawn `magnify` times their length.
void write_detections_png(const Image& line_integrals, const ViewCalibration& view, const std::filesystem::path& png,
                          double magnify = 100);

struct ViewDirection {
  Eigen::Vector3d source_in_holder{0, 0, 1};  // direction from the holder origin to the source
  ViewStatus status = ViewStatus::ok;
  double rms_px = 0;
};
/// The source's direction for a pose T_camera_holder (the camera frame has the source at 0).
Eigen::Vector3d source_direction_in_holder(const Rigid& T_camera_holder);
void write_view_directions_png(const std::vector<ViewDirection>& views, double threshold_px, const std::filesystem::path& png);

/// The pictures `ctk calibrate` writes beside its geometry: `<stem>.residuals.png`,
/// `<stem>.directions.png` and three views drawn (`<stem>.view-NNNN.png`: the median and the worst
/// calibrated view, the first rejected one). Returns the file names written.
std::vector<std::string> write_calibration_pictures(const ScanDescription& scan, const ScanCalibration& c, double threshold_px,
                                                    const std::filesystem::path& stem);

}  // namespace ctk

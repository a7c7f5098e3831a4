#pragma once
// A whole scan in batch: every view in parallel from its image and the first-guess pose the scan
// predicts (robot FK, or given matrices); a view that fails never stops the batch, it is
// rejected or skipped with its reason (no pose, unreadable image, too few spheres, residual).
#include <functional>
#include <map>
#include <vector>

#include "ctk/calib/view_calibration.hpp"
#include "ctk/core/communicator.hpp"
#include "ctk/geom/scan.hpp"

namespace ctk {

struct ScanCalibration {
  Geometry geometry;                   // ctk-geometry/1, one entry per projection
  std::vector<ViewCalibration> views;  // details, same order
  double seconds = 0;
  int taken_over = 0;            // views an earlier run had finished (BatchControl::done)
  int left_undone = 0;           // views not started when a stop was asked for
  double residual_limit_px = 0;  // the residual a view was allowed (residual_limit_px)
};

/// What a batch takes from an earlier, interrupted run, and hands on as it goes.
struct BatchControl {
  const std::map<int, ViewCalibration>* done = nullptr;      // views an earlier run finished: taken as they are
  std::function<void(int, const ViewCalibration&)> on_view;  // each view this run finishes (calls serialised)
  std::function<bool()> stop_requested;                      // true: the views not yet started are left undone
};

/// How one view is seen: a declared source drift moves the focal spot, i.e. the principal point
/// moves with it and the pose is shifted by the spot's offset (P = K' [R | t - s]).
struct ViewCamera {
  Eigen::Matrix3d K;                       // K' of the moved spot
  Rigid from_nominal = Rigid::Identity();  // camera frame of the nominal spot -> of the moved one
  ProjectionMatrix P(const Rigid& T_camera_holder) const { return ProjectionMatrix::compose(K, from_nominal * T_camera_holder); }
};
ViewCamera view_camera(const ScanDescription& scan, int view);

/// Poses from the images alone; robot_prior.hpp's combine_with_robot then adds the robot's prior
/// (`ctk calibrate` does, unless --image-only). Throws InputError for problems of the scan as a whole (no holder, fewer than 6
/// spheres, unreadable flat or dark); per-view problems end up in the views. Over several `ranks`
/// (every rank calling with the same arguments), each calibrates the views dealt to it and every
/// rank receives all of them; `control` is then one process's and must be null, and `progress`
/// counts this rank's views.
ScanCalibration calibrate_scan(const ScanDescription& scan, const CalibrationOptions& options,
                               const std::function<void(int, int)>& progress = {}, const BatchControl* control = nullptr,
                               const Communicator& ranks = single_process());

/// Only the listed views, the others "skipped": a sample calibrated before the batch (to measure
/// an undeclared holder wall, for instance).
ScanCalibration calibrate_scan_views(const ScanDescription& scan, const std::vector<int>& views,
                                     const CalibrationOptions& options, const Communicator& ranks = single_process());

/// Same, starting each view from a calibrated geometry's pose instead of the robot's (views not
/// ok there are skipped): the detections and matches behind an existing calibration.
ScanCalibration recalibrate_scan(const ScanDescription& scan, const Geometry& calibrated, const CalibrationOptions& options,
                                 const std::function<void(int, int)>& progress = {});

/// Only the listed views, each from the calibrated geometry's pose, the others "skipped".
ScanCalibration recalibrate_scan_views(const ScanDescription& scan, const Geometry& calibrated, const std::vector<int>& views,
                                       const CalibrationOptions& options);

}  // namespace ctk

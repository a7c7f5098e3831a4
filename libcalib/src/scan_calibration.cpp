#include "ctk/calib/scan_calibration.hpp"

#include <algorithm>
#include <atomic>
#include <chrono>

#include "ctk/core/error.hpp"
#include "ctk/geom/nominal_geometry.hpp"
#include "ctk/core/parallel.hpp"
#include "ctk/proj/projection_reading.hpp"

namespace ctk {

namespace {

// The first guess of each view: a pose, or why there is none.
struct FirstGuess {
  std::optional<Rigid> T_camera_holder;
  std::string reason;
};

ScanCalibration calibrate_views(const ScanDescription& scan, const std::vector<FirstGuess>& guesses,
                                const CalibrationOptions& options, const std::function<void(int, int)>& progress,
                                const BatchControl* control) {
  const auto start = std::chrono::steady_clock::now();
  options.validate();
  if (!scan.holder) throw InputError("scan", "holder", "calibration needs the holder's spheres (missing)");
  if (static_cast<int>(scan.holder->spheres_mm.size()) < options.min_spheres)
    throw InputError("scan", "holder.spheres_mm",
                     "has " + std::to_string(scan.holder->spheres_mm.size()) + " spheres; a pose needs at least " +
                         std::to_string(options.min_spheres));
  const std::optional<FlatDark> flat_dark = read_flat_dark(scan);
  const int n = scan.projections.count;

  ScanCalibration result;
  result.views.resize(static_cast<std::size_t>(n));
  int done = 0;
  std::atomic<int> left_undone{0};
  std::vector<char> finished(static_cast<std::size_t>(n), 0);
  parallel_for_dynamic(n, [&](int v) {
    ViewCalibration& out = result.views[static_cast<std::size_t>(v)];
    const FirstGuess& guess = guesses[static_cast<std::size_t>(v)];
    if (control && control->done) {
      if (const auto earlier = control->done->find(v); earlier != control->done->end()) {
        out = earlier->second;
        finished[static_cast<std::size_t>(v)] = 2;
#pragma omp critical(ctk_calibration_progress)
        if (progress) progress(++done, n);
        return;
      }
    }
    if (control && control->stop_requested && control->stop_requested()) {
      ++left_undone;
      return;
    }
    if (!guess.T_camera_holder) {
      out.status = ViewStatus::skipped;
      out.reason = "no pose: " + guess.reason;
    } else {
      try {
        const Image image = read_line_integrals(scan, v, flat_dark);
        const ViewCamera camera = view_camera(scan, v);
        out = calibrate_view(image, camera.K, camera.from_nominal * *guess.T_camera_holder, *scan.holder, scan.detector, options,
                             scan.distortion);
        if (out.T_camera_holder) out.T_camera_holder = camera.from_nominal.inverse() * *out.T_camera_holder;
      } catch (const InputError& e) {
        out = ViewCalibration{};
        out.status = ViewStatus::rejected;
        out.reason = std::string("unreadable image: ") + e.what();
      } catch (const std::exception& e) {
        // Whatever else one view's data provokes is that view's rejection, never the batch's end.
        out = ViewCalibration{};
        out.status = ViewStatus::rejected;
        out.reason = std::string("calibration failed: ") + e.what();
      }
    }
    finished[static_cast<std::size_t>(v)] = 1;
#pragma omp critical(ctk_calibration_progress)
    {
      if (control && control->on_view) control->on_view(v, out);
      if (progress) progress(++done, n);
    }
  });
  result.left_undone = left_undone;
  result.taken_over = static_cast<int>(std::count(finished.begin(), finished.end(), 2));

  result.geometry.detector = scan.detector;
  for (int v = 0; v < n; ++v) {
    const ViewCalibration& c = result.views[static_cast<std::size_t>(v)];
    GeometryView g;
    g.index = v;
    g.projection = scan.projections.file_name(v);
    g.status = c.status;
    g.reason = c.reason;
    if (c.status == ViewStatus::ok) {
      g.P = c.P;
      g.rms_px = c.rms_px;
      g.spheres_used = c.spheres_used;
    }
    result.geometry.views.push_back(g);
  }
  result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return result;
}

}  // namespace

ViewCamera view_camera(const ScanDescription& scan, int view) {
  const Eigen::Vector3d s = scan.source_offset_mm(view);
  ViewCamera camera;
  camera.K = scan.intrinsics().K();
  camera.K(0, 2) += s.x() / scan.detector.pitch_u_mm;
  camera.K(1, 2) += s.y() / scan.detector.pitch_v_mm;
  camera.from_nominal.translation() = -s;
  return camera;
}

namespace {

std::vector<FirstGuess> nominal_guesses(const ScanDescription& scan) {
  std::vector<FirstGuess> guesses;
  for (const NominalView& nominal : nominal_views(scan)) {
    FirstGuess g{nominal.T_camera_holder, nominal.reason};
    if (!g.T_camera_holder && nominal.P) g.T_camera_holder = nominal.P->decompose().T_camera_frame;
    guesses.push_back(g);
  }
  return guesses;
}

std::vector<FirstGuess> calibrated_guesses(const ScanDescription& scan, const Geometry& calibrated) {
  if (static_cast<int>(calibrated.views.size()) != scan.projections.count)
    throw InputError(calibrated.source(), json_key("views"),
                     "has " + std::to_string(calibrated.views.size()) + " views; the scan has " +
                         std::to_string(scan.projections.count) + " projections");
  std::vector<FirstGuess> guesses;
  for (const GeometryView& v : calibrated.views) {
    FirstGuess g;
    if (v.status == ViewStatus::ok && v.P)
      g.T_camera_holder = v.P->decompose().T_camera_frame;
    else
      g.reason = "not calibrated in the given geometry" + (v.reason.empty() ? std::string() : ": " + v.reason);
    guesses.push_back(g);
  }
  return guesses;
}

// The guesses of the listed views; the others have none, so their views are skipped.
std::vector<FirstGuess> only(std::vector<FirstGuess> guesses, const std::vector<int>& views) {
  std::vector<char> wanted(guesses.size(), 0);
  for (int v : views)
    if (v >= 0 && v < static_cast<int>(guesses.size())) wanted[static_cast<std::size_t>(v)] = 1;
  for (std::size_t v = 0; v < guesses.size(); ++v)
    if (!wanted[v]) guesses[v] = FirstGuess{std::nullopt, "not in the sample"};
  return guesses;
}

}  // namespace

ScanCalibration calibrate_scan(const ScanDescription& scan, const CalibrationOptions& options,
                               const std::function<void(int, int)>& progress, const BatchControl* control) {
  return calibrate_views(scan, nominal_guesses(scan), options, progress, control);
}

ScanCalibration calibrate_scan_views(const ScanDescription& scan, const std::vector<int>& views,
                                     const CalibrationOptions& options) {
  return calibrate_views(scan, only(nominal_guesses(scan), views), options, {}, nullptr);
}

ScanCalibration recalibrate_scan(const ScanDescription& scan, const Geometry& calibrated, const CalibrationOptions& options,
                                 const std::function<void(int, int)>& progress) {
  return calibrate_views(scan, calibrated_guesses(scan, calibrated), options, progress, nullptr);
}

ScanCalibration recalibrate_scan_views(const ScanDescription& scan, const Geometry& calibrated, const std::vector<int>& views,
                                       const CalibrationOptions& options) {
  return calibrate_views(scan, only(calibrated_guesses(scan, calibrated), views), options, {}, nullptr);
}

}  // namespace ctk

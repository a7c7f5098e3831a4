#include "ctk/calib/scan_calibration.hpp"

#include <algorithm>
#include <atomic>
#include <chrono>

#include "ctk/calib/calibration_journal.hpp"
#include "ctk/core/error.hpp"
#include "ctk/core/parallel.hpp"
#include "ctk/geom/nominal_geometry.hpp"
#include "ctk/measure/projection_reading.hpp"

namespace ctk {

namespace {

// The first guess of each view: a pose, or why there is none.
struct FirstGuess {
  std::optional<Rigid> T_camera_holder;
  std::string reason;
};

// Spread over ranks, every rank receives the views the others calibrated (as the journal stores
// them: every field, numbers to the last bit).
void share_views(const std::vector<int>& mine, const Communicator& ranks, std::vector<ViewCalibration>& views) {
  nlohmann::json done = nlohmann::json::array();
  for (int v : mine) done.push_back({{"view", v}, {"calibration", view_calibration_to_json(views[static_cast<std::size_t>(v)])}});
  for (const std::string& part : ranks.gather(done.dump()))
    for (const nlohmann::json& entry : nlohmann::json::parse(part)) {
      const int v = entry.at("view").get<int>();
      views[static_cast<std::size_t>(v)] = view_calibration_from_json(entry.at("calibration"), "another rank", "view");
    }
}

// One view from its image, its first guess and the scan's camera; whatever its data provoke is
// its rejection with the reason, never the batch's end.
ViewCalibration calibrate_scan_view(const ScanDescription& scan, int v, const FirstGuess& guess,
                                    const std::optional<FlatDark>& flat_dark, const CalibrationOptions& options) {
  ViewCalibration out;
  if (!guess.T_camera_holder) {
    out.status = ViewStatus::skipped;
    out.reason = "no pose: " + guess.reason;
    return out;
  }
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
    out = ViewCalibration{};
    out.status = ViewStatus::rejected;
    out.reason = std::string("calibration failed: ") + e.what();
  }
  return out;
}

// The views' matrices (ok views) and reasons (the others) as a calibrated geometry.
Geometry calibrated_geometry(const ScanDescription& scan, const std::vector<ViewCalibration>& views) {
  Geometry geometry;
  geometry.detector = scan.detector;
  geometry.origin = "calibrated";
  for (std::size_t v = 0; v < views.size(); ++v) {
    const ViewCalibration& c = views[v];
    GeometryView g;
    g.index = static_cast<int>(v);
    g.projection = scan.projections.file_name(static_cast<int>(v));
    g.status = c.status;
    g.reason = c.reason;
    if (c.status == ViewStatus::ok) {
      g.P = c.P;
      g.rms_px = c.rms_px;
      g.spheres_used = c.spheres_used;
    }
    geometry.views.push_back(g);
  }
  return geometry;
}

ScanCalibration calibrate_views(const ScanDescription& scan, const std::vector<FirstGuess>& guesses,
                                const CalibrationOptions& options, const std::function<void(int, int)>& progress,
                                const BatchControl* control, const Communicator& ranks) {
  const auto start = std::chrono::steady_clock::now();
  options.validate();
  if (control && ranks.size() > 1)
    throw std::invalid_argument(
        "calibrate_views: an earlier run's views and stop requests are one process's, not a spread run's");
  if (!scan.holder) throw InputError("scan", "holder", "calibration needs the holder's spheres (missing)");
  if (static_cast<int>(scan.holder->spheres_mm.size()) < options.min_spheres)
    throw InputError("scan", "holder.spheres_mm",
                     "has " + std::to_string(scan.holder->spheres_mm.size()) + " spheres; a pose needs at least " +
                         std::to_string(options.min_spheres));
  const std::optional<FlatDark> flat_dark = read_flat_dark(scan);
  const int n = scan.projections.count;
  // This rank's views, dealt in turn so that each rank's share spans the trajectory.
  std::vector<int> mine;
  for (int v = ranks.rank(); v < n; v += ranks.size()) mine.push_back(v);
  const int share = static_cast<int>(mine.size());

  ScanCalibration result;
  result.views.resize(static_cast<std::size_t>(n));
  int done = 0;
  std::atomic<int> left_undone{0};
  std::vector<char> finished(static_cast<std::size_t>(n), 0);
  parallel_for_dynamic(share, [&](int k) {
    const int v = mine[static_cast<std::size_t>(k)];
    ViewCalibration& out = result.views[static_cast<std::size_t>(v)];
    const FirstGuess& guess = guesses[static_cast<std::size_t>(v)];
    if (control && control->done) {
      if (const auto earlier = control->done->find(v); earlier != control->done->end()) {
        out = earlier->second;
        finished[static_cast<std::size_t>(v)] = 2;
#pragma omp critical(ctk_calibration_progress)
        if (progress) progress(++done, share);
        return;
      }
    }
    if (control && control->stop_requested && control->stop_requested()) {
      ++left_undone;
      return;
    }
    out = calibrate_scan_view(scan, v, guess, flat_dark, options);
    finished[static_cast<std::size_t>(v)] = 1;
#pragma omp critical(ctk_calibration_progress)
    {
      if (control && control->on_view) control->on_view(v, out);
      if (progress) progress(++done, share);
    }
  });
  if (ranks.size() > 1) share_views(mine, ranks, result.views);
  result.residual_limit_px = residual_limit_px(result.views, options);
  for (ViewCalibration& v : result.views)
    if (v.residual_decides) judge_residual(v, result.residual_limit_px);
  result.left_undone = left_undone;
  result.taken_over = static_cast<int>(std::count(finished.begin(), finished.end(), 2));

  result.geometry = calibrated_geometry(scan, result.views);
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
                               const std::function<void(int, int)>& progress, const BatchControl* control,
                               const Communicator& ranks) {
  return calibrate_views(scan, nominal_guesses(scan), options, progress, control, ranks);
}

ScanCalibration calibrate_scan_views(const ScanDescription& scan, const std::vector<int>& views,
                                     const CalibrationOptions& options, const Communicator& ranks) {
  return calibrate_views(scan, only(nominal_guesses(scan), views), options, {}, nullptr, ranks);
}

ScanCalibration recalibrate_scan(const ScanDescription& scan, const Geometry& calibrated, const CalibrationOptions& options,
                                 const std::function<void(int, int)>& progress) {
  return calibrate_views(scan, calibrated_guesses(scan, calibrated), options, progress, nullptr, single_process());
}

ScanCalibration recalibrate_scan_views(const ScanDescription& scan, const Geometry& calibrated, const std::vector<int>& views,
                                       const CalibrationOptions& options) {
  return calibrate_views(scan, only(calibrated_guesses(scan, calibrated), views), options, {}, nullptr, single_process());
}

}  // namespace ctk

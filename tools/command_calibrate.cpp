// ctk calibrate: every view's projection matrix from the helix spheres in its image, the robot's
// forward kinematics (or given matrices) as the first guess; writes ctk-geometry/1 and a report.
// Each finished view is journaled as it completes, so an interrupted run continues (--resume).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <functional>
#include <iostream>
#include <map>
#include <memory>

#include "commands.hpp"
#include "ctk/geom/output_set.hpp"
#include "ctk/geom/run_files.hpp"
#include "option_checks.hpp"
#include "ctk/geom/statistics.hpp"
#include "ctk/calib/calibration_journal.hpp"
#include "ctk/calib/calibration_pictures.hpp"
#include "ctk/calib/holder_wall.hpp"
#include "ctk/calib/robot_prior.hpp"
#include "ctk/calib/scan_calibration.hpp"
#include "ctk/geom/atomic_write.hpp"
#include "ctk/geom/nominal_geometry.hpp"
#include "ctk/proj/projection_reading.hpp"
#include "interruption.hpp"
#include "progress.hpp"

namespace ctk::tools {

namespace {

namespace fs = std::filesystem;

struct CalibrateOptions {
  fs::path scan, out = "geometry.json", report;
  CalibrationOptions calibration;
  bool image_only = false;  // no robot prior
  bool resume = false;
};

// What a journal's views belong to: the same scan (its content) and the options a view depends on.
nlohmann::json calibration_run(const CalibrateOptions& o, const ScanDescription& scan) {
  const CalibrationOptions& c = o.calibration;
  return {{"scan", fs::absolute(o.scan).lexically_normal().string()},
          {"scan_content", std::to_string(std::hash<std::string>{}(scan_to_json(scan).dump()))},
          {"min_spheres", c.min_spheres},
          {"max_rms_px", c.max_rms_px},
          {"search_px", c.search_px},
          {"robust_px", c.robust_px},
          {"max_first_guess_error_deg", c.max_first_guess_error_deg}};
}

nlohmann::json robot_prior_json(const RobotPriorFit& p) {
  if (!p.applied) return {{"applied", false}, {"reason", p.reason}};
  auto offset = [](const double* x) {
    return nlohmann::json{{"rotation_deg", {x[0] * 180 / M_PI, x[1] * 180 / M_PI, x[2] * 180 / M_PI}},
                          {"translation_mm", {x[3], x[4], x[5]}}};
  };
  return {{"applied", true},
          {"views", p.views},
          {"repeatability_measured", {{"translation_mm", p.sigma_mm}, {"rotation_deg", p.sigma_deg}}},
          {"robot_model",
           {{"robot_base_frame", offset(p.model.base)},
            {"holder_mount", offset(p.model.mount)},
            {"note",
             "fitted together only to place the prior; on a trajectory that turns few joints they trade off against each "
             "other and are not meaningful one by one (ctk diagnose attributes such offsets)"}}},
          {"inconsistent_views", p.inconsistent_views},
          {"median_rotation_sigma_deg", {{"image", p.image_rotation_sigma_deg}, {"combined", p.combined_rotation_sigma_deg}}}};
}

nlohmann::json report_json(const ScanCalibration& c, const CalibrateOptions& o) {
  nlohmann::json views = nlohmann::json::array();
  std::vector<double> rms, depth_sigma, across_sigma;
  int ok = 0, rejected = 0, skipped = 0;
  for (std::size_t v = 0; v < c.views.size(); ++v) {
    const ViewCalibration& r = c.views[v];
    nlohmann::json j = {
        {"index", v}, {"status", to_string(r.status)}, {"detections", r.detections}, {"spheres_used", r.spheres_used}};
    if (!r.reason.empty()) j["reason"] = r.reason;
    if (r.P) {
      j["rms_px"] = r.rms_px;
      j["translation_sigma_mm"] = {r.translation_sigma_mm[0], r.translation_sigma_mm[1], r.translation_sigma_mm[2]};
      j["rotation_sigma_deg"] = r.rotation_sigma_deg;
    }
    views.push_back(j);
    if (r.status == ViewStatus::ok) {
      ++ok;
      rms.push_back(r.rms_px);
      depth_sigma.push_back(r.translation_sigma_mm[2]);
      across_sigma.push_back(std::max(r.translation_sigma_mm[0], r.translation_sigma_mm[1]));
    } else if (r.status == ViewStatus::rejected) {
      ++rejected;
    } else {
      ++skipped;
    }
  }
  return {{"format", "ctk-calibration-report/1"},
          {"scan", o.scan.string()},
          {"geometry", o.out.string()},
          {"summary",
           {{"views", c.views.size()},
            {"ok", ok},
            {"rejected", rejected},
            {"skipped", skipped},
            {"median_rms_px", median(rms)},
            {"median_translation_sigma_across_beam_mm", median(across_sigma)},
            {"median_translation_sigma_along_beam_mm", median(depth_sigma)},
            {"seconds", c.seconds},
            {"views_per_second", c.seconds > 0 ? static_cast<double>(c.views.size()) / c.seconds : 0.0}}},
          {"options",
           {{"min_spheres", o.calibration.min_spheres},
            {"max_rms_px", o.calibration.max_rms_px},
            {"search_px", o.calibration.search_px}}},
          {"views", views}};
}

// The pictures beside the geometry: residual per view, view directions, and three views drawn
// (the median and the worst calibrated view, the first rejected one). Returns their names.
std::vector<std::string> write_pictures(const ScanDescription& scan, const ScanCalibration& c, const CalibrateOptions& o) {
  const fs::path stem = fs::path(o.out).replace_extension("");
  auto named = [&](const std::string& what) { return fs::path(stem.string() + "." + what + ".png"); };
  std::vector<std::string> written;
  write_residual_per_view_png(c.views, o.calibration.max_rms_px, named("residuals"));
  written.push_back(named("residuals").filename().string());

  const std::vector<NominalView> nominal = nominal_views(scan);
  std::vector<ViewDirection> directions;
  for (std::size_t v = 0; v < c.views.size(); ++v) {
    const ViewCalibration& r = c.views[v];
    std::optional<Rigid> T = r.T_camera_holder ? r.T_camera_holder : nominal[v].T_camera_holder;
    if (!T && nominal[v].P) T = nominal[v].P->decompose().T_camera_frame;
    if (T) directions.push_back({source_direction_in_holder(*T), r.status, r.rms_px});
  }
  write_view_directions_png(directions, o.calibration.max_rms_px, named("directions"));
  written.push_back(named("directions").filename().string());

  std::vector<std::size_t> ok, shown;
  for (std::size_t v = 0; v < c.views.size(); ++v)
    if (c.views[v].status == ViewStatus::ok) ok.push_back(v);
  std::sort(ok.begin(), ok.end(), [&](std::size_t a, std::size_t b) { return c.views[a].rms_px < c.views[b].rms_px; });
  if (!ok.empty()) shown = {ok[ok.size() / 2], ok.back()};
  for (std::size_t v = 0; v < c.views.size(); ++v)
    if (c.views[v].status == ViewStatus::rejected && c.views[v].radius_px > 0) {
      shown.push_back(v);
      break;
    }
  const std::optional<FlatDark> flat_dark = read_flat_dark(scan);
  for (std::size_t v : shown) {
    char what[32];
    std::snprintf(what, sizeof what, "view-%04zu", v);
    if (std::find(written.begin(), written.end(), named(what).filename().string()) != written.end()) continue;
    write_detections_png(read_line_integrals(scan, static_cast<int>(v), flat_dark), c.views[v], named(what));
    written.push_back(named(what).filename().string());
  }
  return written;
}

fs::path report_file(const CalibrateOptions& o) {
  return o.report.empty() ? fs::path(o.out).replace_extension(".report.json") : o.report;
}

void run_calibrate(const CalibrateOptions& o) {
  const ScanDescription scan = read_scan(o.scan);
  RunFiles files;
  require_projection_files(scan, o.scan.string(), "projections.count");
  files.scan("--scan", o.scan, scan);
  files.output("--out", o.out);
  files.output("--report", report_file(o));
  const fs::path journal_file = fs::path(o.out).replace_extension(".journal");
  files.output("the journal beside --out", journal_file);
  files.output_family("pictures beside --out", fs::path(o.out).replace_extension("").string() + ".", ".png");
  files.check();
  OutputSet outputs;  // published together, after the last is written
  for (const auto& w : scan.warnings) std::cerr << "warning: " << w << "\n";
  // Every finished view is journaled at once: Ctrl-C or a kill loses none, and --resume goes on.
  const nlohmann::json run = calibration_run(o, scan);
  std::unique_ptr<CalibrationJournal> journal;
  if (o.resume) {
    if (!fs::exists(journal_file))
      throw InputError("--resume", "", "no calibration journal at " + journal_file.string() + " to continue");
    journal = CalibrationJournal::resume(journal_file, run);
    std::cout << "continuing: " << journal->done().size() << " views were calibrated by the interrupted run ("
              << journal_file.string() << ")\n";
  } else {
    if (fs::exists(journal_file))
      std::cout << "note: " << journal_file.string()
                << " holds an interrupted run's views; this run starts afresh (--resume continues it)\n";
    journal = std::make_unique<CalibrationJournal>(journal_file, run);
  }
  const std::map<int, ViewCalibration> earlier = journal->done();
  const InterruptionWatch watch;
  BatchControl control;
  control.done = &earlier;
  control.on_view = [&](int view, const ViewCalibration& result) { journal->record(view, result); };
  control.stop_requested = [] { return InterruptionWatch::requested(); };
  Progress progress("calibrate", "views");
  ScanCalibration c = calibrate_scan(scan, o.calibration, std::ref(progress), &control);
  if (c.left_undone > 0)
    throw Interrupted("stopped with " + std::to_string(c.left_undone) + " of " + std::to_string(scan.projections.count) +
                      " views to go; the finished ones are in " + journal_file.string() +
                      ": run the same command with --resume to continue");
  // A holder whose wall the scan does not declare: measured from the images, and the views it
  // cost (a sphere on the wall's silhouette taken for a misfit) calibrated again with it.
  std::optional<WallMeasurement> wall;
  if (scan.holder && !scan.holder->wall) {
    const auto start = std::chrono::steady_clock::now();
    wall = measure_holder_wall(scan, c);
    if (wall &&
        std::any_of(c.views.begin(), c.views.end(), [](const ViewCalibration& v) { return v.status == ViewStatus::rejected; })) {
      ScanDescription with_wall = scan;
      with_wall.holder->wall = wall->wall;
      std::map<int, ViewCalibration> kept;
      for (std::size_t v = 0; v < c.views.size(); ++v)
        if (c.views[v].status != ViewStatus::rejected) kept[static_cast<int>(v)] = c.views[v];
      BatchControl again;
      again.done = &kept;
      const double seconds = c.seconds;
      c = calibrate_scan(with_wall, o.calibration, {}, &again);
      c.seconds += seconds;
    }
    c.seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  }
  RobotPriorFit prior;
  prior.reason = "switched off (--image-only)";
  if (!o.image_only) {
    const auto start = std::chrono::steady_clock::now();
    prior = combine_with_robot(scan, c);
    c.seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  }
  write_geometry(c.geometry, o.out);
  const fs::path report = report_file(o);
  nlohmann::json j = report_json(c, o);
  j["robot_prior"] = robot_prior_json(prior);
  if (scan.holder && scan.holder->wall)
    j["holder_wall"] = {{"declared", true},
                        {"inner_radius_mm", scan.holder->wall->inner_radius_mm},
                        {"outer_radius_mm", scan.holder->wall->outer_radius_mm}};
  else if (wall)
    j["holder_wall"] = {{"declared", false},
                        {"measured",
                         {{"inner_radius_mm", wall->wall.inner_radius_mm},
                          {"outer_radius_mm", wall->wall.outer_radius_mm},
                          {"inner_sigma_mm", wall->inner_sigma_mm},
                          {"outer_sigma_mm", wall->outer_sigma_mm},
                          {"views", wall->views}}}};
  else if (scan.holder)
    j["holder_wall"] = {{"declared", false}, {"measured", nullptr}};
  j["pictures"] = write_pictures(scan, c, o);
  write_text_atomically(report, j.dump(2) + "\n");
  const auto& s = j.at("summary");
  outputs.publish();
  journal->remove();
  if (c.taken_over > 0) std::cout << c.taken_over << " views taken from the interrupted run, the others calibrated now\n";
  std::cout << "calibrated " << s.at("ok") << " of " << s.at("views") << " views (" << s.at("rejected") << " rejected, "
            << s.at("skipped") << " skipped) in " << c.seconds << " s (" << s.at("views_per_second").get<double>()
            << " views/s); median reprojection RMS " << s.at("median_rms_px").get<double>() << " px; median pose uncertainty "
            << s.at("median_translation_sigma_across_beam_mm").get<double>() * 1000 << " um across the beam, "
            << s.at("median_translation_sigma_along_beam_mm").get<double>() * 1000 << " um along it\n";
  if (wall)
    std::cout << "holder wall not declared by the scan; measured in " << wall->views << " views: inner radius "
              << wall->wall.inner_radius_mm << " +- " << wall->inner_sigma_mm << " mm, outer " << wall->wall.outer_radius_mm
              << " +- " << wall->outer_sigma_mm << " mm (declare it as holder.wall to skip this)\n";
  else if (scan.holder && !scan.holder->wall)
    std::cout << "holder wall not declared by the scan and not measurable (fewer than 3 views see the holder from the side)\n";
  if (prior.applied)
    std::cout << "poses combined with the robot's prior over " << prior.views << " views: repeatability measured "
              << prior.sigma_mm << " mm, " << prior.sigma_deg << " deg; median rotation uncertainty "
              << prior.image_rotation_sigma_deg << " deg (image alone) -> " << prior.combined_rotation_sigma_deg << " deg; "
              << prior.inconsistent_views.size() << " views disagree with the robot beyond both noises\n";
  else
    std::cout << "poses from the images alone: " << prior.reason << "\n";
  int listed = 0;
  for (std::size_t v = 0; v < c.views.size() && listed < 20; ++v)
    if (c.views[v].status != ViewStatus::ok) {
      std::cout << "  view " << v << ": " << to_string(c.views[v].status) << " — " << c.views[v].reason << "\n";
      ++listed;
    }
  std::cout << "geometry written to " << o.out.string() << ", report to " << report.string() << "\n";
}

}  // namespace

void register_calibrate(CLI::App& app) {
  auto o = std::make_shared<CalibrateOptions>();
  CLI::App* cmd = app.add_subcommand("calibrate", "Calibrate every view of a scan from the helix spheres in its image");
  cmd->add_option("--scan", o->scan, "scan.json (ctk-scan/1) with a holder section")->required()->check(CLI::ExistingFile);
  cmd->add_option("--out", o->out, "Geometry to write (ctk-geometry/1)")->capture_default_str();
  cmd->add_option("--report", o->report, "Report (JSON; default: <out>.report.json)");
  cmd->add_option("--min-spheres", o->calibration.min_spheres, "Fewer matched spheres: view rejected")
      ->check(CLI::Range(6, 1000))
      ->capture_default_str();
  cmd->add_option("--max-rms", o->calibration.max_rms_px, "Larger reprojection RMS (px): view rejected")
      ->check(positive_number)
      ->capture_default_str();
  cmd->add_option("--search", o->calibration.search_px, "How far (px) the first guess may misplace the sphere pattern")
      ->check(positive_number)
      ->capture_default_str();
  cmd->add_flag("--image-only", o->image_only,
                "Poses from the images alone (default: combined with the robot's prior, its base, mount and repeatability "
                "measured on the scan)");
  cmd->add_flag("--resume", o->resume,
                "Continue an interrupted run: the views it finished (journaled beside --out, .journal) are taken as they are, "
                "the others calibrated; same scan and options");
  cmd->callback([o] { run_calibrate(*o); });
}

}  // namespace ctk::tools

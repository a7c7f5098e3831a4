#include "ctk/calib/calibration_run.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <map>
#include <sstream>
#include <vector>

#include "ctk/core/provenance.hpp"
#include "ctk/core/statistics.hpp"

namespace ctk {

namespace {

double seconds_since(std::chrono::steady_clock::time_point t) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
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

}  // namespace

CalibrationRun run_calibration(const ScanDescription& scan, const CalibrationRunOptions& o,
                               const std::function<void(int, int)>& progress, const BatchControl* control,
                               const Communicator& ranks) {
  o.validate();
  CalibrationRun run;
  run.options = o.calibration;
  run.has_holder = scan.holder.has_value();
  if (scan.holder && scan.holder->wall) run.declared_wall = scan.holder->wall;
  ScanCalibration& c = run.calibration;
  // A holder whose wall (or the wall's ends) the scan does not declare: measured first in a sample
  // of views that see it from the side, then every view calibrated with it as if declared (its
  // shadow part of the spheres' background, the spheres on its silhouette kept).
  double wall_seconds = 0;
  ScanDescription with_wall = scan;
  if (wall_to_measure(scan)) {
    const auto start = std::chrono::steady_clock::now();
    run.wall = measure_holder_wall(scan, calibrate_scan_views(scan, wall_sample_views(scan), o.calibration, ranks));
    if (run.wall) with_wall.holder->wall = modelled_wall(scan, *run.wall);
    wall_seconds = seconds_since(start);
  }
  // The spheres' contrast loss over their background (a polychromatic beam, scatter), measured in
  // a sample of views with the wall as modelled, then applied to every view when measured above
  // zero.
  const auto contrast_start = std::chrono::steady_clock::now();
  const std::vector<int> sample = contrast_sample_views(scan.projections.count);
  run.contrast_loss = measure_contrast_loss(
      [&](const CalibrationOptions& trial) { return calibrate_scan_views(with_wall, sample, trial, ranks); }, o.calibration);
  if (run.contrast_loss->used) run.options.contrast_loss = run.contrast_loss->rate;
  wall_seconds += seconds_since(contrast_start);
  c = calibrate_scan(with_wall, run.options, progress, control, ranks);
  c.seconds += wall_seconds;
  if (c.left_undone > 0) return run;
  run.prior.reason = "switched off (--image-only)";
  if (!o.image_only) {
    const auto start = std::chrono::steady_clock::now();
    run.prior = combine_with_robot(scan, c);
    c.seconds += seconds_since(start);
  }
  return run;
}

nlohmann::json CalibrationRun::summary() const {
  const ScanCalibration& c = calibration;
  std::vector<double> rms, depth_sigma, across_sigma;
  int ok = 0, rejected = 0, skipped = 0;
  for (const ViewCalibration& r : c.views) {
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
  return {{"views", c.views.size()},
          {"ok", ok},
          {"rejected", rejected},
          {"skipped", skipped},
          {"median_rms_px", median(rms)},
          {"residual_limit_px", c.residual_limit_px},
          {"median_translation_sigma_across_beam_mm", median(across_sigma)},
          {"median_translation_sigma_along_beam_mm", median(depth_sigma)},
          {"seconds", c.seconds},
          {"views_per_second", c.seconds > 0 ? static_cast<double>(c.views.size()) / c.seconds : 0.0}};
}

nlohmann::json CalibrationRun::report() const {
  nlohmann::json views = nlohmann::json::array();
  for (std::size_t v = 0; v < calibration.views.size(); ++v) {
    const ViewCalibration& r = calibration.views[v];
    nlohmann::json j = {
        {"index", v}, {"status", to_string(r.status)}, {"detections", r.detections}, {"spheres_used", r.spheres_used}};
    if (!r.reason.empty()) j["reason"] = r.reason;
    if (r.P) {
      j["rms_px"] = r.rms_px;
      j["translation_sigma_mm"] = {r.translation_sigma_mm[0], r.translation_sigma_mm[1], r.translation_sigma_mm[2]};
      j["rotation_sigma_deg"] = r.rotation_sigma_deg;
    }
    views.push_back(j);
  }
  nlohmann::json j = {
      {"format", "ctk-calibration-report/1"},
      {"provenance", provenance()},
      {"summary", summary()},
      {"options", {{"min_spheres", options.min_spheres}, {"max_rms_px", options.max_rms_px}, {"search_px", options.search_px}}},
      {"views", views}};
  j["robot_prior"] = robot_prior_json(prior);
  if (contrast_loss) j["contrast_loss"] = to_json(*contrast_loss);
  if (declared_wall) {
    j["holder_wall"] = {{"declared", true},
                        {"inner_radius_mm", declared_wall->inner_radius_mm},
                        {"outer_radius_mm", declared_wall->outer_radius_mm}};
    if (declared_wall->ends_mm)
      j["holder_wall"]["ends_mm"] = {declared_wall->ends_mm->x(), declared_wall->ends_mm->y()};
    else
      j["holder_wall"]["measured"] = wall ? to_json(*wall) : nlohmann::json();  // the ends looked for
  } else if (has_holder) {
    j["holder_wall"] = {{"declared", false}, {"measured", wall ? to_json(*wall) : nlohmann::json()}};
  }
  return j;
}

std::string CalibrationRun::brief() const {
  const nlohmann::json s = summary();
  std::ostringstream b;
  b << "calibrated " << s.at("ok") << " of " << s.at("views") << " views (" << s.at("rejected") << " rejected, "
    << s.at("skipped") << " skipped) in " << calibration.seconds << " s (" << s.at("views_per_second").get<double>()
    << " views/s); median reprojection RMS " << s.at("median_rms_px").get<double>() << " px; median pose uncertainty "
    << s.at("median_translation_sigma_across_beam_mm").get<double>() * 1000 << " um across the beam, "
    << s.at("median_translation_sigma_along_beam_mm").get<double>() * 1000 << " um along it";
  if (calibration.residual_limit_px > options.max_rms_px)
    b << "\nevery view's residual is high (a holder whose spheres are each a little off, or a detector effect the model "
         "lacks): views rejected above "
      << calibration.residual_limit_px << " px, twice the scan's median, instead of " << options.max_rms_px
      << " px; ctk diagnose tells which";
  return b.str();
}

std::string CalibrationRun::wall_and_prior() const {
  std::ostringstream b;
  if (const std::string line = has_holder ? wall_line(declared_wall, wall) : ""; !line.empty()) b << line << "\n";
  if (contrast_loss) b << contrast_loss_line(*contrast_loss) << "\n";
  if (prior.applied)
    b << "poses combined with the robot's prior over " << prior.views << " views: repeatability measured " << prior.sigma_mm
      << " mm, " << prior.sigma_deg << " deg; median rotation uncertainty " << prior.image_rotation_sigma_deg
      << " deg (image alone) -> " << prior.combined_rotation_sigma_deg << " deg; " << prior.inconsistent_views.size()
      << " views disagree with the robot beyond both noises";
  else
    b << "poses from the images alone: " << prior.reason;
  return b.str();
}

std::string CalibrationRun::next_command(const std::filesystem::path& scan_file,
                                         const std::filesystem::path& geometry_file) const {
  if (has_holder)
    return "ctk diagnose --scan " + scan_file.string() + " --geometry " + geometry_file.string() + " --out " +
           (geometry_file.parent_path() / "diagnosis.json").string();
  return "ctk reconstruct --scan " + scan_file.string() + " --geometry " + geometry_file.string() + " --out volume.nrrd";
}

}  // namespace ctk

#include "ctk/calib/diagnosis_run.hpp"

#include <sstream>

#include "ctk/calib/robot_prior.hpp"
#include "ctk/core/error.hpp"

namespace ctk {

namespace {

// The robot's repeatability as the scan shows it (the scatter of the image poses about the
// robot's model, less the image's own share; maximum likelihood, as calibrate's robot prior
// measures it), unless the user stated it: a robot worse than its datasheet would otherwise make
// every scan look structured, and a better one hide small effects. Returns what was done.
std::string set_repeatability(const DiagnosisRunOptions& o, const ScanDescription& scan, const ScanCalibration& c,
                              DiagnosisOptions& d) {
  if (o.repeatability_mm) d.robot_sigma_mm = *o.repeatability_mm;
  if (o.repeatability_deg) d.robot_sigma_deg = *o.repeatability_deg;
  std::ostringstream said;
  if ((o.repeatability_mm && o.repeatability_deg) || !scan.panda) return said.str();
  ScanCalibration copy = c;
  const RobotPriorFit prior = combine_with_robot(scan, copy);
  if (!prior.applied) {
    said << "robot repeatability not measured (" << prior.reason << "): assumed " << d.robot_sigma_mm << " mm, "
         << d.robot_sigma_deg << " deg";
    return said.str();
  }
  if (!o.repeatability_mm) d.robot_sigma_mm = prior.sigma_mm;
  if (!o.repeatability_deg) d.robot_sigma_deg = prior.sigma_deg;
  said << "robot repeatability measured on the scan: " << prior.sigma_mm << " mm, " << prior.sigma_deg << " deg (3-D RMS)";
  return said.str();
}

}  // namespace

void DiagnosisRunOptions::validate() const {
  diagnosis.validate();
  calibration.validate();
  // A stated repeatability is a physical spread: positive, and below what no robot CT setup
  // would run with (10 mm, 10 deg).
  if (repeatability_mm)
    require_option(*repeatability_mm > 0 && *repeatability_mm <= 10, "DiagnosisRunOptions.repeatability_mm",
                   "a length in (0, 10] mm", *repeatability_mm);
  if (repeatability_deg)
    require_option(*repeatability_deg > 0 && *repeatability_deg <= 10, "DiagnosisRunOptions.repeatability_deg",
                   "an angle in (0, 10] deg", *repeatability_deg);
}

DiagnosisRun run_diagnosis(const ScanDescription& scan, const Geometry& geometry, const DiagnosisRunOptions& o,
                           const std::function<void(int, int)>& progress, const std::function<void(const std::string&)>& log) {
  o.validate();
  const auto say = [&](const std::string& line) {
    if (log && !line.empty()) log(line);
  };
  if (!scan.holder) throw InputError(scan.folder.string(), "holder", "the diagnosis needs the holder's spheres (missing)");
  DiagnosisRun run;
  // A wall the scan does not declare is measured in the views that see it from the side (from
  // the given poses) and then modelled as if declared, as ctk calibrate does.
  ScanDescription modelled = scan;
  run.wall_declared = scan.holder->wall.has_value();
  if (wall_to_measure(scan)) {
    run.wall = measure_holder_wall(scan, recalibrate_scan_views(scan, geometry, wall_sample_views(scan), o.calibration));
    if (run.wall) modelled.holder->wall = modelled_wall(scan, *run.wall);
    say(wall_line(scan.holder->wall, run.wall));
  }
  // The spheres measured as ctk calibrate measures them, with the contrast loss the scan shows:
  // measured as calibrate measures it (from the scan's first guesses, not the given poses, so the
  // two agree to the last bit when the wall was declared).
  CalibrationOptions calibration = o.calibration;
  const std::vector<int> sample = contrast_sample_views(scan.projections.count);
  run.contrast_loss = measure_contrast_loss(
      [&](const CalibrationOptions& trial) { return calibrate_scan_views(modelled, sample, trial); }, calibration);
  if (run.contrast_loss.used) calibration.contrast_loss = run.contrast_loss.rate;
  say(contrast_loss_line(run.contrast_loss));
  // The detections and matches behind the given calibration, each view started from its pose.
  const ScanCalibration c = recalibrate_scan(modelled, geometry, calibration, progress);
  DiagnosisOptions options = o.diagnosis;
  run.repeatability = set_repeatability(o, scan, c, options);
  say(run.repeatability);
  run.observations = observe_scan(scan, c, options);
  if (run.observations.views.size() < 10)
    throw InputError(
        geometry.source(), "views",
        "only " + std::to_string(run.observations.views.size()) + " calibrated views; the diagnosis needs at least 10");
  std::ostringstream noise;
  noise << run.observations.views.size() << " views, detection noise " << run.observations.centre_sigma_px << " px per axis";
  say(noise.str());
  run.diagnosis = diagnose(run.observations, options, log);
  run.corrected = corrected_scan(modelled, run.diagnosis);
  return run;
}

nlohmann::json DiagnosisRun::report() const {
  nlohmann::json j = diagnosis_to_json(diagnosis, observations);
  if (wall) j["holder_wall"] = {{"declared", wall_declared}, {"measured", to_json(*wall)}};
  j["contrast_loss"] = to_json(contrast_loss);
  return j;
}

std::string DiagnosisRun::brief() const {
  const Diagnosis& d = diagnosis;
  std::ostringstream b;
  // The verdict first: what was found and how sure, or that nothing was.
  b.precision(3);
  b << "found: ";
  bool any = false;
  for (const EffectFinding& f : d.effects)
    if (f.accepted) {
      b << (any ? ", " : "") << effect_name(f.effect) << " (held-out t " << f.z << " against " << f.threshold_z << ")";
      any = true;
    }
  if (!any) b << "no effect beyond chance (at most " << 100 * d.false_acceptance_rate << " % false acceptances per scan)";
  if (!d.unexplained.empty()) b << "; structure no effect explains: " << d.unexplained.front().where;
  b << "\nbaseline " << d.baseline.rms_px << " px RMS (held out " << d.baseline.heldout_rms_px << ")";
  if (observations.setup.robot) b << ", robot prediction error " << d.baseline.fk_translation_rms_mm << " mm RMS";
  for (const EffectFinding& f : d.effects)
    if (f.accepted) {
      b << "\naccepted " << effect_name(f.effect) << ": " << f.before.rms_px << " -> " << f.after.rms_px << " px";
      if (observations.setup.robot)
        b << ", robot prediction " << f.before.fk_translation_rms_mm << " -> " << f.after.fk_translation_rms_mm << " mm";
      if (!f.confounded_with.empty()) {
        b << " (confounded with";
        for (Effect e : f.confounded_with) b << " " << effect_name(e);
        b << ")";
      }
    }
  if (whole_holder_off(d))
    b << "\nevery sphere of the holder is off its declared centre (a printed holder): measure it once (ctk holder measure) "
         "and declare the holder file it writes";
  return b.str();
}

std::string DiagnosisRun::next_command(const std::filesystem::path& scan_file, const std::filesystem::path& geometry_file,
                                       const std::filesystem::path& corrected_file) const {
  if (whole_holder_off(diagnosis))
    return "ctk holder measure --scan " + scan_file.string() + " --geometry " + geometry_file.string() + " --out holder.json";
  if (diagnosis.accepted.empty())
    return "ctk reconstruct --scan " + scan_file.string() + " --geometry " + geometry_file.string() + " --out volume.nrrd";
  return "ctk calibrate --scan " + corrected_file.string() + " --out " +
         (corrected_file.parent_path() / "recalibrated.json").string();
}

}  // namespace ctk

// ctk diagnose: which named physical effect explains the residual a calibration leaves; writes
// the ctk-diagnosis/1 report, a corrected scan file and pictures (diagnosis-report.md).
#include <filesystem>
#include <iostream>
#include <optional>

#include "commands.hpp"
#include "ctk/geom/output_set.hpp"
#include "ctk/geom/run_files.hpp"
#include "option_checks.hpp"
#include "ctk/calib/diagnosis.hpp"
#include "ctk/calib/diagnosis_pictures.hpp"
#include "ctk/calib/robot_prior.hpp"
#include "ctk/geom/atomic_write.hpp"
#include "progress.hpp"

namespace ctk::tools {

namespace {

namespace fs = std::filesystem;

struct DiagnoseOptions {
  fs::path scan, geometry, out = "diagnosis.json", corrected;
  DiagnosisOptions diagnosis;
  CalibrationOptions calibration;
  std::optional<double> repeatability_mm, repeatability_deg;  // absent: measured on the scan
};

// The robot's repeatability as the scan shows it (the scatter of the image poses about the
// robot's model, less the image's own share; maximum likelihood, as calibrate's robot prior
// measures it), unless the user stated it: a robot worse than its datasheet would otherwise make
// every scan look structured, and a better one hide small effects.
void set_repeatability(const DiagnoseOptions& o, const ScanDescription& scan, const ScanCalibration& c, DiagnosisOptions& d) {
  if (o.repeatability_mm) d.robot_sigma_mm = *o.repeatability_mm;
  if (o.repeatability_deg) d.robot_sigma_deg = *o.repeatability_deg;
  if ((o.repeatability_mm && o.repeatability_deg) || !scan.panda) return;
  ScanCalibration copy = c;
  const RobotPriorFit prior = combine_with_robot(scan, copy);
  if (!prior.applied) {
    std::cout << "robot repeatability not measured (" << prior.reason << "): assumed " << d.robot_sigma_mm << " mm, "
              << d.robot_sigma_deg << " deg\n";
    return;
  }
  if (!o.repeatability_mm) d.robot_sigma_mm = prior.sigma_mm;
  if (!o.repeatability_deg) d.robot_sigma_deg = prior.sigma_deg;
  std::cout << "robot repeatability measured on the scan: " << prior.sigma_mm << " mm, " << prior.sigma_deg << " deg (3-D RMS)\n";
}

void run_diagnose(const DiagnoseOptions& o) {
  const ScanDescription scan = read_scan(o.scan);
  const fs::path stem = fs::path(o.out).replace_extension("");
  const fs::path corrected_file = o.corrected.empty() ? fs::path(stem.string() + ".corrected-scan.json") : o.corrected;
  RunFiles files;
  require_projection_files(scan, o.scan.string(), "projections.count");
  files.scan("--scan", o.scan, scan);
  files.input("--geometry", o.geometry);
  files.output("--out", o.out);
  files.output("--corrected-scan", corrected_file);
  files.output_family("pictures beside --out", stem.string() + ".", ".png");
  files.check();
  OutputSet outputs;  // published together, after the last is written
  for (const auto& w : scan.warnings) std::cerr << "warning: " << w << "\n";
  if (!scan.holder) throw InputError(o.scan.string(), "holder", "the diagnosis needs the holder's spheres (missing)");
  const Geometry geometry = read_geometry(o.geometry);
  // The detections and matches behind the given calibration, each view started from its pose.
  Progress progress("detect", "views");
  const ScanCalibration c = recalibrate_scan(scan, geometry, o.calibration, std::ref(progress));
  DiagnosisOptions diagnosis = o.diagnosis;
  set_repeatability(o, scan, c, diagnosis);
  const ScanObservations observations = observe_scan(scan, c, diagnosis);
  if (observations.views.size() < 10)
    throw InputError(o.geometry.string(), "views",
                     "only " + std::to_string(observations.views.size()) + " calibrated views; the diagnosis needs at least 10");
  std::cout << observations.views.size() << " views, detection noise " << observations.centre_sigma_px << " px per axis\n";
  const Diagnosis d = diagnose(observations, diagnosis, [](const std::string& s) { std::cout << s << std::endl; });

  nlohmann::json report = diagnosis_to_json(d, observations);
  report["scan"] = o.scan.string();
  report["geometry"] = o.geometry.string();
  report["pictures"] = write_diagnosis_pictures(d, observations, stem);
  const ScanDescription corrected = corrected_scan(scan, d);
  // Relative names in the corrected scan must still find the projections: write it beside the
  // original unless the user chose a place, and say where its data lives.
  nlohmann::json corrected_json = scan_to_json(corrected);
  if (fs::absolute(corrected_file).parent_path() != fs::absolute(o.scan).parent_path())
    std::cerr << "note: " << corrected_file.string() << " names its files relative to " << o.scan.parent_path().string()
              << "; keep it beside " << o.scan.filename().string() << " to use it\n";
  write_text_atomically(corrected_file, corrected_json.dump(2) + "\n");
  report["corrected_scan"] = corrected_file.string();
  write_text_atomically(o.out, report.dump(2) + "\n");

  outputs.publish();
  std::cout << "baseline " << d.baseline.rms_px << " px RMS (held out " << d.baseline.heldout_rms_px << ")";
  if (observations.setup.robot) std::cout << ", robot prediction error " << d.baseline.fk_translation_rms_mm << " mm RMS";
  std::cout << "\n";
  for (const EffectFinding& f : d.effects)
    if (f.accepted) {
      std::cout << "accepted " << effect_name(f.effect) << ": " << f.before.rms_px << " -> " << f.after.rms_px << " px";
      if (observations.setup.robot)
        std::cout << ", robot prediction " << f.before.fk_translation_rms_mm << " -> " << f.after.fk_translation_rms_mm << " mm";
      if (!f.confounded_with.empty()) {
        std::cout << " (confounded with";
        for (Effect e : f.confounded_with) std::cout << " " << effect_name(e);
        std::cout << ")";
      }
      std::cout << "\n";
    }
  std::cout << "unexplained structure: " << report["unexplained"]["note"].get<std::string>() << "\n"
            << "report " << o.out.string() << ", corrected scan " << corrected_file.string() << "\n";
}

}  // namespace

void register_diagnose(CLI::App& app) {
  auto o = std::make_shared<DiagnoseOptions>();
  CLI::App* cmd = app.add_subcommand(
      "diagnose", "Find the physical effect behind a calibration's residual; report, corrected scan, pictures");
  cmd->add_option("--scan", o->scan, "scan.json (ctk-scan/1) with a holder")->required()->check(CLI::ExistingFile);
  cmd->add_option("--geometry", o->geometry, "Its calibrated geometry (ctk-geometry/1, from ctk calibrate)")
      ->required()
      ->check(CLI::ExistingFile);
  cmd->add_option("--out", o->out, "Report to write (ctk-diagnosis/1)")->capture_default_str();
  cmd->add_option("--corrected-scan", o->corrected, "Corrected scan to write (default: <out>.corrected-scan.json)");
  cmd->add_option("--robot-repeatability-mm", o->repeatability_mm,
                  "Robot repeatability (3-D RMS) the prior assumes; default: measured on the scan")
      ->check(positive_number);
  cmd->add_option("--robot-repeatability-deg", o->repeatability_deg, "Same, rotation; default: measured on the scan")
      ->check(positive_number);
  cmd->callback([o] { run_diagnose(*o); });
}

}  // namespace ctk::tools

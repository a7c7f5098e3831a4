// ctk diagnose: which named physical effect explains the residual a calibration leaves; writes
// the ctk-diagnosis/1 report, a corrected scan file and pictures (diagnosis-report.md).
#include <filesystem>
#include <iostream>
#include <optional>

#include "commands.hpp"
#include "ctk/calib/diagnosis_pictures.hpp"
#include "ctk/calib/diagnosis_run.hpp"
#include "ctk/core/atomic_write.hpp"
#include "ctk/core/output_set.hpp"
#include "ctk/geom/run_files.hpp"
#include "interruption.hpp"
#include "option_checks.hpp"
#include "progress.hpp"
#include "run_page.hpp"

namespace ctk::tools {

namespace {

namespace fs = std::filesystem;

struct DiagnoseOptions {
  fs::path scan, geometry, out = "diagnosis.json", corrected;
  DiagnosisRunOptions run;
};

void run_diagnose(const DiagnoseOptions& o) {
  const ScanDescription scan = read_scan(o.scan);
  const fs::path stem = fs::path(o.out).replace_extension("");
  const fs::path corrected_file = o.corrected.empty() ? fs::path(stem.string() + ".corrected-scan.json") : o.corrected;
  RunFiles files;
  files.scan_to_read("--scan", o.scan, scan);
  files.input("--geometry", o.geometry);
  files.output("--out", o.out);
  files.output("--corrected-scan", corrected_file);
  files.output("the HTML report beside --out", stem.string() + ".html");
  files.output_family("pictures beside --out", stem.string() + ".", ".png");
  files.check();
  OutputSet outputs;  // published together, after the last is written
  for (const auto& w : scan.warnings) std::cerr << "warning: " << w << "\n";
  if (!scan.holder) throw InputError(o.scan.string(), "holder", "the diagnosis needs the holder's spheres (missing)");
  const Geometry geometry = geometry_for_scan(scan, read_geometry(o.geometry));
  std::cout << "geometry: " << geometry.description() << "\n";
  Progress progress("detect", "views");
  const DiagnosisRun run = stoppable("diagnose stopped by Ctrl-C: nothing written", [&] {
    return run_diagnosis(scan, geometry, o.run, std::ref(progress), [](const std::string& s) { std::cout << s << std::endl; });
  });
  const Diagnosis& d = run.diagnosis;
  const ScanObservations& observations = run.observations;

  nlohmann::json report = run.report();
  report["scan"] = o.scan.string();
  report["geometry"] = o.geometry.string();
  const std::vector<std::string> pictures = write_diagnosis_pictures(d, observations, stem);
  report["pictures"] = pictures;
  // Relative names in the corrected scan find the same files from where it is written.
  write_scan(relocated_scan(run.corrected, corrected_file), corrected_file);
  report["corrected_scan"] = corrected_file.string();
  write_text_atomically(o.out, report.dump(2) + "\n");
  write_and_name_run_page("diagnose", run.brief(), report, pictures_beside(o.out, pictures), stem.string() + ".html",
                          run.next_command(o.scan, o.geometry, corrected_file));

  outputs.publish();
  std::cout << run.brief() << "\n";
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
  cmd->add_option("--robot-repeatability-mm", o->run.repeatability_mm,
                  "Robot repeatability (3-D RMS) the prior assumes; default: measured on the scan")
      ->check(positive_number);
  cmd->add_option("--robot-repeatability-deg", o->run.repeatability_deg, "Same, rotation; default: measured on the scan")
      ->check(positive_number);
  cmd->add_option("--false-acceptance-rate", o->run.diagnosis.false_acceptance_rate,
                  "Probability that chance alone accepts any effect in a scan that has none")
      ->check(CLI::Range(1e-9, 0.5))
      ->capture_default_str();
  cmd->callback([o] { run_diagnose(*o); });
}

}  // namespace ctk::tools

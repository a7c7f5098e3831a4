// ctk refine: close the loop on a scan without fiducials (circular orbits). Reconstructs from half
// of the views, predicts the other half, and accepts the named effects (detector offset and roll,
// axis tilt, magnification, angular blur, beam hardening) that predict held-out views better than
// chance. Writes the report (ctk-diagnosis/1, mode "markerless"), the refined per-view matrices, a
// scan file that uses them, and central slices before and after.
#include <chrono>
#include <cmath>
#include <filesystem>
#include <iostream>
#include <optional>

#include "commands.hpp"
#include "ctk/core/atomic_write.hpp"
#include "ctk/core/error.hpp"
#include "ctk/core/image_io.hpp"
#include "ctk/core/output_set.hpp"
#include "ctk/geom/nominal_geometry.hpp"
#include "ctk/geom/run_files.hpp"
#include "ctk/recon/refine_scan.hpp"
#include "ctk/recon/refinement_pictures.hpp"
#include "interruption.hpp"
#include "measurement_report.hpp"
#include "option_checks.hpp"
#include "progress.hpp"
#include "run_page.hpp"

namespace ctk::tools {

namespace {

namespace fs = std::filesystem;

struct RefineOptions {
  fs::path scan, geometry, out;
  RefineScanOptions options;
};

fs::path beside(const fs::path& out, const std::string& suffix) { return out.parent_path() / (out.stem().string() + suffix); }

void run_refine(const RefineOptions& o) {
  const auto start = std::chrono::steady_clock::now();
  o.options.validate();
  const ScanDescription scan = read_scan(o.scan);
  RunFiles files;
  files.scan_to_read("--scan", o.scan, scan);
  files.input("--geometry", o.geometry);
  files.output("--out", o.out);
  for (const char* suffix : {".geometry.json", ".scan.json", ".before.png", ".after.png", ".difference.png", ".pattern.png",
                             ".pixel-offsets.tif", ".html"})
    files.output(std::string("beside --out: ") + suffix, beside(o.out, suffix));
  files.check();
  OutputSet outputs;  // published together, after the last is written
  for (const auto& w : scan.warnings) std::cerr << "warning: " << w << "\n";
  const Geometry geometry = geometry_or_nominal(scan, o.scan, o.geometry);
  std::cout << "geometry: " << (o.geometry.empty() ? geometry.origin + " (from the scan file)" : geometry.description()) << "\n";
  Progress reading("reading projections", "views");
  auto log = [&](const std::string& line) {
    const double t = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    std::cout << "[" << static_cast<int>(t) << " s] " << line << std::endl;
  };
  const RefineScanSummary s = stoppable("refine stopped by Ctrl-C: nothing written",
                                        [&] { return refine_scan(scan, geometry, o.options, log, std::ref(reading)); });
  const RefinementResult& r = s.result;
  if (s.clamped_pixels > 0) std::cout << "clamped " << s.clamped_pixels << " pixels\n";
  report_masked_and_left_out(s.masked_pixels, s.left_out);
  if (s.conjugate)
    std::cout << "cross-check: conjugate rays " << s.conjugate->u0_px << " +- " << s.conjugate->standard_error_px
              << " px, the loop " << s.loop_u0_px << " px (difference " << s.conjugate->u0_px - s.loop_u0_px << " px)\n";

  const fs::path geometry_file = beside(o.out, ".geometry.json"), scan_file = beside(o.out, ".scan.json");
  write_geometry(s.refined, geometry_file);
  // The corrected scan names its files relative to where it is written, and its summary
  // intrinsics state what the refined matrices encode.
  ScanDescription corrected = relocated_scan(scan, scan_file);
  corrected.panda.reset();
  corrected.matrices = MatricesPoseSource{geometry_file.filename().string(), s.refined};
  state_matrices_intrinsics(corrected);
  write_scan(corrected, scan_file);

  nlohmann::json report = s.report();
  report["scan"] = o.scan.string();
  report["corrected_geometry"] = geometry_file.string();
  report["corrected_scan"] = scan_file.string();
  nlohmann::json lacks = nlohmann::json::array();
  if (r.model.blur_arc_rad > 0) lacks.push_back("angular_blur");
  if (r.model.hardening_c2 != 0) lacks.push_back("beam_hardening");
  if (!r.model.pixel_offset.empty())
    lacks.push_back("pixel offsets (pixel_gain / column_gain): in " + beside(o.out, ".pixel-offsets.tif").string());
  if (!lacks.empty()) report["corrected_scan_lacks"] = lacks;
  report["seconds"] = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  write_text_atomically(o.out, report.dump(2) + "\n");

  const std::vector<fs::path> pictures = pictures_beside(o.out, write_refinement_pictures(r, beside(o.out, "")));
  if (!r.model.pixel_offset.empty())
    write_image_float(Image{scan.detector.cols, scan.detector.rows, r.model.pixel_offset}, beside(o.out, ".pixel-offsets.tif"));
  write_and_name_run_page("refine", s.brief(), report, pictures, beside(o.out, ".html"));
  outputs.publish();
  std::cout << s.brief() << "\n";
  for (const auto& e : r.effects)
    if (e.accepted) std::cout << "accepted " << e.name << " " << e.parameters.dump() << " +- " << e.uncertainty.dump() << "\n";
  std::cout << "report " << o.out.string() << ", refined matrices " << geometry_file.string() << ", scan " << scan_file.string()
            << ", slices " << beside(o.out, ".before.png").string() << " / .after.png, what is left on the detector "
            << beside(o.out, ".pattern.png").string() << "\n";
}

}  // namespace

void register_refine(CLI::App& app) {
  auto o = std::make_shared<RefineOptions>();
  CLI::App* cmd = app.add_subcommand(
      "refine", "Markerless loop for circular scans: find and fit the effects the geometry lacks, judged on held-out views");
  cmd->add_option("--scan", o->scan, "scan.json (ctk-scan/1)")->required()->check(CLI::ExistingFile);
  cmd->add_option("--geometry", o->geometry, "Per-view matrices to start from (default: the scan's nominal geometry)")
      ->check(CLI::ExistingFile);
  cmd->add_option("--out", o->out, "Report (ctk-diagnosis/1); beside it <stem>.geometry.json, <stem>.scan.json, slices")
      ->required();
  cmd->add_option("--coarsening", o->options.coarsening, "Voxel of the held-out predictions, in pixels seen at the axis")
      ->check(CLI::Range(1.0, 8.0))
      ->capture_default_str();
  cmd->add_option("--blur-arc", o->options.blur_arc_deg,
                  "Arc of rotation each view is known to integrate, degrees (sets the blur scan's step)")
      ->check(non_negative_number);
  cmd->add_option("--z", o->options.z_accept, "Acceptance: held-out improvement in standard errors")
      ->check(positive_number)
      ->capture_default_str();
  cmd->add_option("--effects", o->options.effects, "Candidates (default: all)")
      ->check(CLI::IsMember({"detector_offset", "detector_roll", "axis_tilt", "magnification", "angular_blur", "beam_hardening",
                             "pixel_gain", "column_gain"}));
  cmd->callback([o] { run_refine(*o); });
}

}  // namespace ctk::tools

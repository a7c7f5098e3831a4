// ctk holder: a holder measured sphere by sphere from one scan of it (holder self-calibration),
// and a helix fitted to any holder's centres (holder_measurement.hpp, helix_fit.hpp).
#include <filesystem>
#include <iostream>

#include "commands.hpp"
#include "ctk/calib/holder_measurement.hpp"
#include "ctk/calib/holder_pictures.hpp"
#include "ctk/core/atomic_write.hpp"
#include "ctk/core/output_set.hpp"
#include "ctk/geom/holder_file.hpp"
#include "ctk/geom/run_files.hpp"
#include "interruption.hpp"
#include "option_checks.hpp"
#include "progress.hpp"
#include "run_page.hpp"

namespace ctk::tools {

namespace {

namespace fs = std::filesystem;

struct MeasureOptions {
  fs::path scan, geometry, out = "holder.json";
  HolderMeasurementOptions run;
};

void run_measure(const MeasureOptions& o) {
  const ScanDescription scan = read_scan(o.scan);
  RunFiles files;
  files.scan_to_read("--scan", o.scan, scan);
  files.input("--geometry", o.geometry);
  files.output("--out", o.out);
  const fs::path stem = fs::path(o.out).replace_extension("");
  files.output("the HTML report beside --out", stem.string() + ".html");
  files.output_family("pictures beside --out", stem.string() + ".", ".png");
  files.check();
  OutputSet outputs;
  for (const auto& w : scan.warnings) std::cerr << "warning: " << w << "\n";
  if (!scan.holder) throw InputError(o.scan.string(), "holder", "measuring the holder needs its declared spheres (missing)");
  const Geometry geometry = geometry_for_scan(scan, read_geometry(o.geometry));
  Progress progress("detect", "views");
  // Ctrl-C stops the views being matched; nothing is written before the measurement ends.
  const HolderMeasurement m = stoppable("holder measure stopped by Ctrl-C: nothing written", [&] {
    return run_holder_measurement(scan, geometry, o.run, std::ref(progress),
                                  [](const std::string& s) { std::cout << s << std::endl; });
  });
  const nlohmann::json holder = m.holder_file(o.scan.string());
  write_text_atomically(o.out, holder.dump(2) + "\n");
  const std::vector<fs::path> pictures = pictures_beside(o.out, write_holder_pictures(m, stem));
  write_and_name_run_page(
      "holder measure", m.brief(), holder, pictures, stem.string() + ".html",
      "declare \"holder\": \"" + o.out.filename().string() + "\" in the scans of this holder, then ctk calibrate");
  outputs.publish();
  std::cout << "holder file " << o.out.string() << ": declare it in a scan as \"holder\": \"" << o.out.filename().string()
            << "\" (a path relative to the scan's folder)\n";
}

void run_helix(const fs::path& holder_file) {
  const Holder h = holder_named(holder_file.string());
  const HelixFit fit = fit_helix(h.spheres_mm, h.helix);
  std::cout.precision(4);
  std::cout << "helix through " << h.spheres_mm.size() << " centres: radius " << fit.helix.radius_mm << " mm (declared "
            << h.helix.radius_mm << "), rho " << fit.helix.rho_rad_per_mm << " rad/mm (declared " << h.helix.rho_rad_per_mm
            << "), phase " << fit.helix.phase_rad << " rad, axis tilted " << fit.axis_tilt_rad.x() * 180 / M_PI << ", "
            << fit.axis_tilt_rad.y() * 180 / M_PI << " deg, crossing w = 0 at " << fit.axis_offset_mm.x() << ", "
            << fit.axis_offset_mm.y() << " mm\ncentres off the curve: " << fit.rms_deviation_mm << " mm RMS\n";
  for (std::size_t k = 0; k < fit.deviation_mm.size(); ++k)
    std::cout << "sphere " << k << ": " << fit.deviation_mm[k].norm() << " mm (" << fit.deviation_mm[k].x() << ", "
              << fit.deviation_mm[k].y() << ", " << fit.deviation_mm[k].z() << ")\n";
}

}  // namespace

void register_holder(CLI::App& app) {
  CLI::App* holder = app.add_subcommand("holder", "Measure a holder's spheres from a scan of it; fit a helix to a holder's");
  holder->require_subcommand(1);
  auto o = std::make_shared<MeasureOptions>();
  CLI::App* measure = holder->add_subcommand(
      "measure", "Every sphere's centre from one scan of the holder (60+ well-spread views), with its uncertainty");
  measure->add_option("--scan", o->scan, "scan.json (ctk-scan/1) declaring the holder")->required()->check(CLI::ExistingFile);
  measure->add_option("--geometry", o->geometry, "Its calibrated geometry (ctk-geometry/1, from ctk calibrate)")
      ->required()
      ->check(CLI::ExistingFile);
  measure->add_option("--out", o->out, "Holder file to write (ctk-holder/1)")->capture_default_str();
  measure->add_option("--min-views", o->run.min_views, "Fewest calibrated views to measure from")
      ->check(CLI::Range(10, 1000000))
      ->capture_default_str();
  measure
      ->add_option("--robot-repeatability-mm", o->run.diagnosis.repeatability_mm,
                   "Robot repeatability (3-D RMS); default: measured on the scan")
      ->check(positive_number);
  measure->callback([o] { run_measure(*o); });
  auto file = std::make_shared<fs::path>();
  CLI::App* helix = holder->add_subcommand("helix", "The helix through a holder's centres, each centre's deviation from it");
  helix->add_option("--holder", *file, "ctk-holder/1 file, or a built-in holder (reference, thesis-first)")->required();
  helix->callback([file] { run_helix(*file); });
}

}  // namespace ctk::tools

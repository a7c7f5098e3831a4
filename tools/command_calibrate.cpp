// ctk calibrate: every view's projection matrix from the helix spheres in its image, the robot's
// forward kinematics (or given matrices) as the first guess; writes ctk-geometry/1 and a report.
// Each finished view is journaled as it completes, so an interrupted run continues (--resume).
// Under mpirun the views are dealt to the ranks (no journal: Ctrl-C ends the run) and the first
// rank writes.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <functional>
#include <iostream>
#include <map>
#include <memory>
#include <optional>

#include "commands.hpp"
#include "ctk/calib/calibration_journal.hpp"
#include "ctk/calib/calibration_pictures.hpp"
#include "ctk/calib/calibration_run.hpp"
#include "ctk/core/atomic_write.hpp"
#include "ctk/core/communicator.hpp"
#include "ctk/core/output_set.hpp"
#include "ctk/geom/nominal_geometry.hpp"
#include "ctk/geom/run_files.hpp"
#include "ctk/measure/projection_reading.hpp"
#include "interruption.hpp"
#include "option_checks.hpp"
#include "progress.hpp"
#include "run_page.hpp"

namespace ctk::tools {

namespace {

namespace fs = std::filesystem;

struct CalibrateOptions {
  fs::path scan, out = "geometry.json", report;
  int bin = 1;
  CalibrationOptions calibration;
  bool image_only = false;  // no robot prior
  bool resume = false;
};

// A scan's content as the views depend on it: its JSON without the provenance of whoever wrote it.
std::string scan_content(const ScanDescription& scan) {
  nlohmann::json j = scan_to_json(scan);
  j.erase("provenance");
  return j.dump();
}

// What a journal's views belong to: the same scan (its content) and the options a view depends on.
nlohmann::json calibration_run(const CalibrateOptions& o, const ScanDescription& scan) {
  const CalibrationOptions& c = o.calibration;
  return {{"scan", fs::absolute(o.scan).lexically_normal().string()},
          {"scan_content", std::to_string(std::hash<std::string>{}(scan_content(scan)))},
          {"min_spheres", c.min_spheres},
          {"max_rms_px", c.max_rms_px},
          {"search_px", c.search_px},
          {"robust_px", c.robust_px},
          {"max_first_guess_error_deg", c.max_first_guess_error_deg}};
}

fs::path report_file(const CalibrateOptions& o) {
  return o.report.empty() ? fs::path(o.out).replace_extension(".report.json") : o.report;
}

void run_calibrate(const CalibrateOptions& o) {
  // Ctrl-C from the very start is a request to stop (exit 130 at the first view boundary), not the
  // signal's default end; spread over ranks, mpirun passes it on and every rank ends at once.
  // Watched before the ranks are counted: starting MPI takes a few tenths of a second.
  std::optional<InterruptionWatch> watch;
  watch.emplace();
  if (world().size() > 1) watch.reset();
  const ScanDescription scan = read_scan_binned(o.scan, o.bin);
  RunFiles files;
  files.scan_to_read("--scan", o.scan, scan);
  files.output("--out", o.out);
  files.output("--report", report_file(o));
  files.output("the HTML report beside --report", fs::path(report_file(o)).replace_extension(".html"));
  const fs::path journal_file = fs::path(o.out).replace_extension(".journal");
  files.output("the journal beside --out", journal_file);
  files.output_family("pictures beside --out", fs::path(o.out).replace_extension("").string() + ".", ".png");
  files.check();
  OutputSet outputs;  // published together, after the last is written
  for (const auto& w : scan.warnings) std::cerr << "warning: " << w << "\n";
  const Communicator& ranks = world();
  const bool spread = ranks.size() > 1;
  if (o.resume && spread)
    throw InputError("--resume", "", "a run spread over MPI ranks keeps no journal to continue: run it again");
  // Every finished view is journaled at once: Ctrl-C or a kill loses none, and --resume goes on.
  const nlohmann::json run = calibration_run(o, scan);
  std::unique_ptr<CalibrationJournal> journal;
  std::map<int, ViewCalibration> earlier;
  BatchControl control;
  if (!spread) {
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
    earlier = journal->done();
    control.done = &earlier;
    control.on_view = [&](int view, const ViewCalibration& result) { journal->record(view, result); };
    control.stop_requested = [] { return InterruptionWatch::requested(); };
  } else {
    std::cout << "spread over " << ranks.size() << " ranks: rank r calibrates views r, r + " << ranks.size()
              << ", ...; progress counts the first rank's\n";
  }
  Progress progress("calibrate", "views");
  const CalibrationRun run_result =
      run_calibration(scan, {o.calibration, o.image_only}, std::ref(progress), spread ? nullptr : &control, ranks);
  const ScanCalibration& c = run_result.calibration;
  if (c.left_undone > 0)
    throw Interrupted("stopped with " + std::to_string(c.left_undone) + " of " + std::to_string(scan.projections.count) +
                      " views to go; the finished ones are in " + journal_file.string() +
                      ": run the same command with --resume to continue");
  if (ranks.rank() != 0) return;  // every rank holds the whole calibration: the first writes it
  write_geometry(c.geometry, o.out);
  const fs::path report = report_file(o);
  nlohmann::json j = run_result.report();
  j["scan"] = o.scan.string();
  j["geometry"] = o.out.string();
  const std::vector<std::string> pictures =
      write_calibration_pictures(scan, c, o.calibration.max_rms_px, fs::path(o.out).replace_extension(""));
  j["pictures"] = pictures;
  write_text_atomically(report, j.dump(2) + "\n");
  write_and_name_run_page("calibrate", run_result.brief(), j, pictures_beside(o.out, pictures),
                          fs::path(report).replace_extension(".html"), run_result.next_command(o.scan, o.out));
  outputs.publish();
  if (journal) journal->remove();
  if (c.taken_over > 0) std::cout << c.taken_over << " views taken from the interrupted run, the others calibrated now\n";
  std::cout << run_result.brief() << "\n" << run_result.wall_and_prior() << "\n";
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
  cmd->add_option("--bin", o->bin, "Bin the detector n x n (counts summed, pitch scaled; the matrices address binned pixels)")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
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

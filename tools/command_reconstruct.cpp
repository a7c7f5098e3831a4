// ctk reconstruct: a volume in the holder frame from a scan's projections and per-view matrices,
// by weighted least squares (conjugate gradients), SIRT, or FDK for circular scans. Prints the memory plan first and
// refuses a run that cannot fit; writes the volume (one NRRD file), PNG previews of the three
// central slices and a JSON log, published together. The solver's state is saved every few
// iterations and on Ctrl-C, and --resume continues it.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <iostream>
#include <optional>

#include "commands.hpp"
#include "ctk/geom/output_set.hpp"
#include "ctk/geom/run_files.hpp"
#include "option_checks.hpp"
#include "ctk/geom/atomic_write.hpp"
#include "ctk/geom/error.hpp"
#include "ctk/geom/json_access.hpp"
#include "ctk/geom/nominal_geometry.hpp"
#include "ctk/proj/image_io.hpp"
#include "ctk/proj/joseph_operator.hpp"
#include "ctk/recon/default_volume.hpp"
#include "ctk/recon/fdk.hpp"
#include "ctk/recon/measurements.hpp"
#include "ctk/recon/memory_plan.hpp"
#include "ctk/recon/sirt.hpp"
#include "ctk/recon/solver_state.hpp"
#include "ctk/recon/wls_cg.hpp"
#include "measurement_report.hpp"
#include "interruption.hpp"
#include "progress.hpp"

namespace ctk::tools {

namespace {

namespace fs = std::filesystem;

struct ReconstructOptions {
  fs::path scan, geometry, out;
  std::string method = "wls-cg";
  int iterations = 0;  // 0: the method's default
  double lambda = 0, tolerance = 1e-4;
  std::string regulariser = "identity";
  bool unweighted = false;
  bool as_measured = false;
  std::vector<int> size;
  double voxel_mm = 0;
  bool resume = false;
  int checkpoint_every = 10;
};

// A fingerprint of the data a run solves for: a continued run must see the same numbers.
std::uint64_t fingerprint(const FloatBuffer& data) {
  constexpr std::size_t kChunk = 1 << 20;
  const std::size_t chunks = (data.size() + kChunk - 1) / kChunk;
  std::vector<std::uint64_t> hashes(chunks);
#pragma omp parallel for schedule(static)
  for (std::ptrdiff_t c = 0; c < static_cast<std::ptrdiff_t>(chunks); ++c) {
    const std::size_t begin = static_cast<std::size_t>(c) * kChunk, end = std::min(data.size(), begin + kChunk);
    std::uint64_t h = 1469598103934665603ull;  // FNV-1a over the bits of each value
    for (std::size_t i = begin; i < end; ++i) {
      std::uint32_t bits = 0;
      std::memcpy(&bits, &data[i], sizeof bits);
      h = (h ^ bits) * 1099511628211ull;
    }
    hashes[static_cast<std::size_t>(c)] = h;
  }
  std::uint64_t h = 1469598103934665603ull;
  for (std::uint64_t part : hashes) h = (h ^ part) * 1099511628211ull;
  return h;
}

VolumeLayout volume_layout(const ReconstructOptions& o, const ScanDescription& scan, const std::vector<ProjectionMatrix>& views) {
  VolumeLayout layout = default_volume_layout(scan, views, o.voxel_mm);
  if (!o.size.empty()) {
    std::array<int, 3> size{};
    for (std::size_t a = 0; a < 3; ++a) size[a] = o.size[std::min(a, o.size.size() - 1)];
    layout = VolumeLayout::centred(size, layout.voxel_mm);
  }
  return layout;
}

fs::path preview_file(const fs::path& out, const std::string& slice) { return out.parent_path() / (out.stem().string() + slice); }

void write_previews(const Volume& x, const fs::path& out) {
  const float high = preview_ceiling(x);
  const auto& n = x.layout.size;
  write_slice_png(x, 2, n[2] / 2, 0.0f, high, preview_file(out, "_axial.png"));
  write_slice_png(x, 1, n[1] / 2, 0.0f, high, preview_file(out, "_coronal.png"));
  write_slice_png(x, 0, n[0] / 2, 0.0f, high, preview_file(out, "_sagittal.png"));
}

void run_reconstruct(const ReconstructOptions& o) {
  const auto start = std::chrono::steady_clock::now();
  const ScanDescription scan = read_scan(o.scan);
  RunFiles files;
  require_projection_files(scan, o.scan.string(), "projections.count");
  files.scan("--scan", o.scan, scan);
  files.input("--geometry", o.geometry);
  files.output("--out", o.out);
  files.output("the log beside --out", fs::path(o.out).replace_extension(".log.json"));
  const fs::path state_file = fs::path(o.out).replace_extension(".state");
  files.output("the solver state beside --out", state_file);
  for (const char* slice : {"_axial.png", "_coronal.png", "_sagittal.png"})
    files.output(std::string("the preview beside --out"), preview_file(o.out, slice));
  files.check();
  OutputSet outputs;  // published together, after the last is written
  for (const auto& w : scan.warnings) std::cerr << "warning: " << w << "\n";
  const Geometry geometry = geometry_or_nominal(scan, o.scan, o.geometry);
  const ReconstructionMethod method = o.method == "sirt"  ? ReconstructionMethod::sirt
                                      : o.method == "fdk" ? ReconstructionMethod::fdk
                                                          : ReconstructionMethod::wls_cg;
  const bool weighted =
      method == ReconstructionMethod::wls_cg && !o.unweighted && scan.projections.kind == ProjectionKind::counts;
  const int used = static_cast<int>(geometry.ok_views().size());
  if (used == 0)
    throw InputError(o.geometry.empty() ? o.scan.string() : o.geometry.string(), json_key("views"),
                     "no view is \"ok\": nothing to reconstruct");
  const int described = static_cast<int>(geometry.views.size());
  std::cout << "geometry: " << (o.geometry.empty() ? "nominal (from the scan file)" : o.geometry.string()) << ", " << used
            << " of " << described << " views ok (the others are not used)";
  // A geometry of part of the scan is legitimate (views are matched by index), but so is a slip
  // of the wrong file: say so.
  if (described != scan.projections.count)
    std::cout << "; it describes " << described << " of the scan's " << scan.projections.count << " projections";
  std::cout << "\n";

  // The plan needs the layout, which needs the source distance: from the matrices, before any image.
  std::vector<ProjectionMatrix> ok_matrices;
  for (int i : geometry.ok_views()) ok_matrices.push_back(*geometry.views[static_cast<std::size_t>(i)].P);
  const VolumeLayout layout = volume_layout(o, scan, ok_matrices);
  const MemoryPlan plan = plan_memory(method, layout, used, scan.detector.rows, scan.detector.cols, weighted);
  const std::size_t available = available_memory_bytes();
  std::cout << "volume " << layout.size[0] << " x " << layout.size[1] << " x " << layout.size[2] << " voxels of "
            << layout.voxel_mm.x() << " mm (holder frame, centred on the holder origin)\n"
            << "memory plan (" << to_string(method) << "): " << plan.describe() << "; available "
            << static_cast<double>(available) / 1e9 << " GB\n";
  if (plan.total_bytes() > available)
    throw std::runtime_error("the run needs " + plan.describe() + " but only " +
                             std::to_string(static_cast<double>(available) / 1e9) +
                             " GB are available: use a coarser --voxel, a smaller --size or fewer views");

  Progress reading("reading projections", "views");
  MeasurementOptions reading_options;
  reading_options.statistical_weights = weighted;
  reading_options.undistort = !o.as_measured;
  Measurements m = load_measurements(scan, geometry, reading_options, std::ref(reading));
  if (!m.distortion_note.empty()) std::cout << m.distortion_note << "\n";
  if (m.clamped_pixels > 0)
    std::cout << "clamped " << m.clamped_pixels << " pixels (counts at or below dark, or above the flat)\n";
  report_masked_and_left_out(m, geometry.source());

  const nlohmann::json run = {
      {"scan", fs::absolute(o.scan).lexically_normal().string()},
      {"geometry", o.geometry.empty() ? std::string("nominal") : fs::absolute(o.geometry).lexically_normal().string()},
      {"method", to_string(method)},
      {"weights", weighted ? "poisson" : "unit"},
      {"lambda", o.lambda},
      {"regulariser", o.regulariser},
      {"tolerance", o.tolerance},
      {"volume", {{"size", layout.size}, {"voxel_mm", layout.voxel_mm.x()}}},
      {"views_used", m.view_indices},
      {"data_fingerprint",
       std::to_string(fingerprint(m.line_integrals.data)) + (weighted ? "/" + std::to_string(fingerprint(m.weights.data)) : "")}};
  std::optional<SolverState> saved;
  if (o.resume) {
    if (method == ReconstructionMethod::fdk)
      throw InputError("--resume", "", "fdk is not iterative: there is nothing to continue");
    if (!fs::exists(state_file)) throw InputError("--resume", "", "no saved state at " + state_file.string() + " to continue");
    nlohmann::json saved_run;
    saved = read_solver_state(state_file, saved_run);
    // A saved state continues only the run that saved it: same data, geometry, volume and solver.
    require_same_run(saved_run, run, state_file.string(), "run",
                     "continue with the same inputs and options, or start afresh without --resume");
    std::cout << "continuing " << to_string(method) << " after iteration " << saved->iteration << " (state "
              << state_file.string() << ")\n";
  } else if (fs::exists(state_file) && method != ReconstructionMethod::fdk) {
    std::cout << "note: " << state_file.string()
              << " holds the state of an interrupted run; this run starts afresh (--resume continues it)\n";
  }
  const InterruptionWatch watch;
  Checkpointing checkpointing;
  checkpointing.resume = saved ? &*saved : nullptr;
  checkpointing.every = o.checkpoint_every;
  checkpointing.save = [&](const SolverSnapshot& state) { write_solver_state(state, run, state_file); };
  checkpointing.stop_requested = [] { return InterruptionWatch::requested(); };

  const JosephOperator A(m.matrices, layout, m.line_integrals.rows, m.line_integrals.cols);
  Volume x(layout);
  const int iterations = o.iterations > 0 ? o.iterations : (method == ReconstructionMethod::sirt ? 100 : 30);
  Progress solving(to_string(method), "iterations");
  auto on_iteration = [&](const IterationLog& l) {
    if (l.iteration > 0) solving(l.iteration, iterations);
  };
  SolverReport report;
  if (method == ReconstructionMethod::fdk) {
    // Refuses non-circular scans before any work, with the deviation found.
    const CircularTrajectory circle = fit_circular_trajectory(m.matrices);
    std::cout << "circular trajectory: radius " << circle.radius_mm << " mm, arc " << circle.arc_rad * 180 / M_PI << " deg"
              << (circle.arc_rad < 2 * M_PI - 1e-9 ? " (short scan: Parker weights)" : "") << "\n";
    fdk_reconstruct(m.matrices, m.line_integrals, scan.detector, x);
    report.stop_reason = "FDK (Hann-windowed ramp)";
    report.iterations.push_back({});
  } else if (method == ReconstructionMethod::sirt) {
    report = solve_sirt(A, m.line_integrals, x, {iterations, 1.0, true}, on_iteration, &checkpointing);
  } else {
    WlsOptions w;
    w.iterations = iterations;
    w.tolerance = o.tolerance;
    w.lambda = o.lambda;
    w.regulariser = o.regulariser == "gradient" ? Regulariser::gradient : Regulariser::identity;
    report = solve_wls_cg(A, m.line_integrals, weighted ? &m.weights : nullptr, x, w, on_iteration, &checkpointing);
  }
  if (report.stop_reason == kStoppedOnRequest)
    throw Interrupted("stopped after iteration " + std::to_string(report.iterations.back().iteration) +
                      "; the solver's state is in " + state_file.string() + ": run the same command with --resume to continue");
  if (method == ReconstructionMethod::fdk)
    std::cout << report.stop_reason << "\n";
  else
    std::cout << report.stop_reason << "; cost " << report.iterations.front().cost << " -> " << report.iterations.back().cost
              << "\n";

  write_volume_nrrd(x, o.out);
  write_previews(x, o.out);
  nlohmann::json log = {{"format", "ctk-reconstruction-log/1"},
                        {"scan", o.scan.string()},
                        {"geometry", o.geometry.empty() ? "nominal" : o.geometry.string()},
                        {"method", to_string(method)},
                        {"weights", weighted ? "poisson" : "unit"},
                        {"lambda", o.lambda},
                        {"regulariser", o.regulariser},
                        {"volume",
                         {{"size", layout.size},
                          {"voxel_mm", layout.voxel_mm.x()},
                          {"origin_mm", {layout.origin_mm.x(), layout.origin_mm.y(), layout.origin_mm.z()}}}},
                        {"views_used", m.view_indices},
                        {"clamped_pixels", m.clamped_pixels},
                        {"masked_pixels", m.masked_pixels},
                        {"views_left_out", m.left_out},
                        {"notes", m.notes},
                        {"detector_distortion", m.distortion_note},
                        {"memory_plan", plan.describe()},
                        {"solver", to_json(report)},
                        {"seconds", std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count()}};
  fs::path log_file = o.out;
  log_file.replace_extension(".log.json");
  write_text_atomically(log_file, log.dump(2) + "\n");
  outputs.publish();
  std::error_code ignored;
  fs::remove(state_file, ignored);  // the run is complete: nothing left to continue
  std::cout << "volume written to " << o.out.string() << ", previews *_axial/_coronal/_sagittal.png, log " << log_file.string()
            << "\n";
}

}  // namespace

void register_reconstruct(CLI::App& app) {
  auto o = std::make_shared<ReconstructOptions>();
  CLI::App* cmd = app.add_subcommand("reconstruct", "Reconstruct a volume (holder frame) from a scan and its per-view matrices");
  cmd->add_option("--scan", o->scan, "scan.json (ctk-scan/1)")->required()->check(CLI::ExistingFile);
  cmd->add_option("--geometry", o->geometry, "Per-view matrices (ctk-geometry/1); default: the scan's nominal geometry")
      ->check(CLI::ExistingFile);
  cmd->add_option("--out", o->out, "Volume to write (.nrrd: header and data in one file)")->required();
  cmd->add_option("--method", o->method, "wls-cg, sirt or fdk (circular scans only)")
      ->check(CLI::IsMember({"wls-cg", "sirt", "fdk"}))
      ->capture_default_str();
  cmd->add_option("--iterations", o->iterations, "Iterations (default: 30 for wls-cg, 100 for sirt)")
      ->check(CLI::Range(1, 100000));
  cmd->add_option("--lambda", o->lambda, "Regularisation weight")->check(non_negative_number)->capture_default_str();
  cmd->add_option("--regulariser", o->regulariser, "identity (Tikhonov) or gradient")
      ->check(CLI::IsMember({"identity", "gradient"}))
      ->capture_default_str();
  cmd->add_option("--tolerance", o->tolerance, "Stop when the gradient has fallen by this factor (0 <= tolerance < 1)")
      ->check(fraction_below_one)
      ->capture_default_str();
  cmd->add_flag("--unweighted", o->unweighted, "Unit weights even for counts (plain least squares)");
  cmd->add_flag("--as-measured", o->as_measured,
                "Use the images as measured even when the scan declares a detector distortion (by default they are "
                "resampled onto the matrices' pinhole grid)");
  cmd->add_option("--size", o->size, "Voxels: n (cube) or nx ny nz (default: cover the holder, or the field of view)")
      ->expected(1, 3)
      ->check(CLI::Range(1, 100000));
  cmd->add_option("--voxel", o->voxel_mm, "Voxel size in mm (default: a pixel seen at the holder origin)")
      ->check(positive_number);
  cmd->add_flag(
      "--resume", o->resume,
      "Continue an interrupted run (Ctrl-C or a kill) from the solver state saved beside --out (.state); same inputs and "
      "options, --iterations may grow");
  cmd->add_option("--checkpoint-every", o->checkpoint_every,
                  "Save the solver's state every N iterations (0: only on Ctrl-C); removed when the run completes")
      ->check(CLI::Range(0, 100000))
      ->capture_default_str();
  cmd->callback([o] { run_reconstruct(*o); });
}

}  // namespace ctk::tools

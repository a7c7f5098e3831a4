// ctk reconstruct: a volume in the holder frame from a scan's projections and per-view matrices
// (librecon's run_reconstruction): checks the files, prints the memory plan, saves the solver's
// state every few iterations and on Ctrl-C (--resume continues it), and writes the volume (one
// NRRD file), PNG previews of the three central slices and a JSON log, published together.
// Under mpirun the views (or slabs of the volume) are spread over the ranks and the first rank
// writes.
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <iostream>
#include <optional>

#include "commands.hpp"
#include "ctk/core/atomic_write.hpp"
#include "ctk/core/chart.hpp"
#include "ctk/core/communicator.hpp"
#include "ctk/core/error.hpp"
#include "ctk/core/image_io.hpp"
#include "ctk/core/json_access.hpp"
#include "ctk/core/output_set.hpp"
#include "ctk/core/slice_preview.hpp"
#include "ctk/core/volume_file.hpp"
#include "ctk/geom/nominal_geometry.hpp"
#include "ctk/geom/run_files.hpp"
#include "ctk/proj/slab_split_operator.hpp"
#include "ctk/recon/reconstruction_run.hpp"
#include "interruption.hpp"
#include "measurement_report.hpp"
#include "option_checks.hpp"
#include "progress.hpp"
#include "run_page.hpp"

namespace ctk::tools {

namespace {

namespace fs = std::filesystem;

struct ReconstructOptions {
  fs::path scan, geometry, out;
  int bin = 1;
  // The numbers bound straight into the library's options (and their defaults); the choices
  // below are the library's names, turned into its enums by library_options.
  ReconstructionOptions run;
  std::string method = to_string(run.method);
  std::string regulariser = to_string(run.regulariser);
  std::string preconditioner = to_string(run.preconditioner);
  std::string decomposition = to_string(run.decomposition);
  bool unweighted = false;
  bool as_measured = false;
  std::vector<int> size;
  bool resume = false;
  int checkpoint_every = 10;
};

ReconstructionOptions library_options(const ReconstructOptions& o) {
  ReconstructionOptions r = o.run;
  r.method = reconstruction_method(o.method);
  r.regulariser = regulariser_from_string(o.regulariser);
  r.preconditioner = cg_preconditioner_from_string(o.preconditioner);
  r.decomposition = decomposition_from_string(o.decomposition);
  r.statistical_weights = !o.unweighted;
  r.undistort = !o.as_measured;
  if (o.size.size() == 2)
    throw InputError("--size", "",
                     "expected one value (a cube of n voxels) or three (nx ny nz), got two: " + std::to_string(o.size[0]) + " " +
                         std::to_string(o.size[1]));
  for (std::size_t a = 0; a < 3 && !o.size.empty(); ++a) r.size[a] = o.size[std::min(a, o.size.size() - 1)];
  return r;
}

fs::path preview_file(const fs::path& out, const std::string& slice) { return out.parent_path() / (out.stem().string() + slice); }

// The solver's cost along its iterations, on a log scale relative to the start (a table of
// numbers does not show where a run stopped improving). False when there is nothing to draw
// (FDK, or one iteration).
bool write_convergence(const std::vector<IterationLog>& log, const fs::path& png) {
  if (log.size() < 2 || !(log.front().cost > 0)) return false;
  std::vector<double> relative;
  relative.reserve(log.size());
  for (const IterationLog& l : log) relative.push_back(std::log10(std::max(l.cost / log.front().cost, 1e-12)));
  const double low = std::floor(*std::min_element(relative.begin(), relative.end()) * 2) / 2;
  ChartAxes axes{0,
                 static_cast<double>(log.back().iteration),
                 std::min(low, -0.5),
                 0.1,
                 "convergence",
                 "iteration",
                 "log10(cost / starting cost)"};
  Chart chart(480, 280, axes);
  for (std::size_t i = 1; i < log.size(); ++i)
    chart.line(log[i - 1].iteration, relative[i - 1], log[i].iteration, relative[i], colour::blue, 2);
  for (std::size_t i = 0; i < log.size(); ++i) chart.dot(log[i].iteration, relative[i], colour::blue, 2.5);
  chart.ticks(nice_step(axes.x1 - axes.x0, 6), nice_step(axes.y1 - axes.y0, 5));
  chart.save(png);
  return true;
}

void write_previews(const Volume& x, const fs::path& out) {
  const float high = preview_ceiling(x);
  const auto& n = x.layout.size;
  write_slice_preview(x, 2, n[2] / 2, 0.0f, high, "1/mm", preview_file(out, "_axial.png"));
  write_slice_preview(x, 1, n[1] / 2, 0.0f, high, "1/mm", preview_file(out, "_coronal.png"));
  write_slice_preview(x, 0, n[0] / 2, 0.0f, high, "1/mm", preview_file(out, "_sagittal.png"));
}

// Split into slabs: the first rank writes its slab and takes each other rank's in turn, so no
// rank ever holds the whole volume; the previews' three central slices are copied out on the way
// (their grey scale from those slices).
void write_slabs(const Volume& mine, const VolumeLayout& whole, const Communicator& ranks, const fs::path& out) {
  const auto& n = whole.size;
  const auto slice_of = [&](int nx, int ny, int nz) { return Volume(VolumeLayout::centred({nx, ny, nz}, whole.voxel_mm)); };
  Volume axial = slice_of(n[0], n[1], 1), coronal = slice_of(n[0], 1, n[2]), sagittal = slice_of(1, n[1], n[2]);
  std::vector<int> planes;
  planes.reserve(static_cast<std::size_t>(ranks.size()));
  for (int q = 0; q < ranks.size(); ++q) planes.push_back(slab_planes(n[2], q, ranks.size()).count);
  std::vector<float> received;
  int first_plane = 0;
  const VolumeSlabs slabs{
      whole, planes, [&](int k) {
        std::span<const float> voxels(mine.data.data(), mine.data.size());
        if (k > 0) {
          received.resize(static_cast<std::size_t>(planes[static_cast<std::size_t>(k)]) * static_cast<std::size_t>(n[0]) *
                          static_cast<std::size_t>(n[1]));
          ranks.receive(k, received);
          voxels = received;
        }
        const auto at = [&](int x, int y, int p) {
          return voxels[(static_cast<std::size_t>(p) * static_cast<std::size_t>(n[1]) + static_cast<std::size_t>(y)) *
                            static_cast<std::size_t>(n[0]) +
                        static_cast<std::size_t>(x)];
        };
        for (int p = 0; p < planes[static_cast<std::size_t>(k)]; ++p) {
          const int z = first_plane + p;
          for (int y = 0; y < n[1]; ++y)
            for (int x = 0; x < n[0]; ++x) {
              if (z == n[2] / 2) axial.at(x, y, 0) = at(x, y, p);
              if (y == n[1] / 2) coronal.at(x, 0, z) = at(x, y, p);
              if (x == n[0] / 2) sagittal.at(0, y, z) = at(x, y, p);
            }
        }
        first_plane += planes[static_cast<std::size_t>(k)];
        return voxels;
      }};
  write_volume(slabs, out);
  Volume all_three = slice_of(static_cast<int>(axial.data.size() + coronal.data.size() + sagittal.data.size()), 1, 1);
  std::copy(sagittal.data.begin(), sagittal.data.end(),
            std::copy(coronal.data.begin(), coronal.data.end(),
                      std::copy(axial.data.begin(), axial.data.end(), all_three.data.begin())));
  const float high = preview_ceiling(all_three);
  write_slice_preview(axial, 2, 0, 0.0f, high, "1/mm", preview_file(out, "_axial.png"));
  write_slice_preview(coronal, 1, 0, 0.0f, high, "1/mm", preview_file(out, "_coronal.png"));
  write_slice_preview(sagittal, 0, 0, 0.0f, high, "1/mm", preview_file(out, "_sagittal.png"));
}

// Which views the geometry describes, and how many of the scan's (a geometry of part of the scan
// is legitimate, views being matched by index, but so is a slip of the wrong file: say so).
void say_which_views(const ScanDescription& scan, const Geometry& geometry, bool given) {
  const int described = static_cast<int>(geometry.views.size());
  std::cout << "geometry: " << (!given ? geometry.origin + " (from the scan file)" : geometry.description()) << ", "
            << geometry.ok_views().size() << " of " << described << " views ok (the others are not used)";
  if (described != scan.projections.count)
    std::cout << "; it describes " << described << " of the scan's " << scan.projections.count << " projections";
  std::cout << "\n";
}

void require_state_to_continue(ReconstructionMethod method, bool spread, const fs::path& state_file) {
  if (method == ReconstructionMethod::fdk) throw InputError("--resume", "", "fdk is not iterative: there is nothing to continue");
  if (method == ReconstructionMethod::os_sqs)
    throw InputError("--resume", "", "os-sqs keeps no state to continue (its momentum restarts): run it again");
  if (spread) throw InputError("--resume", "", "a run spread over MPI ranks keeps no state to continue: run it again");
  if (!fs::exists(state_file)) throw InputError("--resume", "", "no saved state at " + state_file.string() + " to continue");
}

// The run told on the console as it goes (its plan, what was read, progress), and its state
// saved beside --out and continued from there.
ReconstructionHooks console_hooks(const ReconstructOptions& o, bool spread, const fs::path& state_file, Progress& reading,
                                  std::optional<Progress>& solving) {
  // A saved state continues only the run that saved it: the same files, data, volume and solver.
  // A file is named by where it is (symbolic links and ".." resolved): the same scan spelt
  // another way is the same scan.
  const auto place = [](const fs::path& p) {
    std::error_code ec;
    const fs::path resolved = fs::weakly_canonical(fs::absolute(p), ec);
    return (ec ? fs::absolute(p).lexically_normal() : resolved).string();
  };
  const nlohmann::json files_used = {{"scan", place(o.scan)},
                                     {"geometry", o.geometry.empty() ? std::string("nominal") : place(o.geometry)}};
  const auto with_files = [files_used](nlohmann::json identity) {
    identity.update(files_used);
    return identity;
  };
  ReconstructionHooks hooks;
  hooks.planned = [spread, &solving](const ReconstructionPlan& plan) {
    const VolumeLayout& l = plan.layout;
    std::cout << "volume " << l.size[0] << " x " << l.size[1] << " x " << l.size[2] << " voxels of " << l.voxel_mm.x()
              << " mm (holder frame, centred on the holder origin)\n"
              << "memory plan (" << to_string(plan.method) << (spread ? ", per rank" : "") << "): " << plan.memory().describe()
              << "; available " << static_cast<double>(plan.available_bytes) / 1e9 << " GB\n";
    if (spread) std::cout << "spread over " << plan.distribution.ranks << " ranks:\n" << plan.distribution.describe() << "\n";
    solving.emplace(to_string(plan.method), "iterations");
  };
  hooks.reading = std::ref(reading);
  hooks.measured = [](const Measurements& m) {
    if (!m.distortion_note.empty()) std::cout << m.distortion_note << "\n";
    if (m.clamped_pixels > 0)
      std::cout << "clamped " << m.clamped_pixels << " pixels (counts at or below dark, or above the flat)\n";
    report_masked_and_left_out(m.masked_pixels, m.left_out);  // run_reconstruction then requires views left
  };
  hooks.iterating = [&solving](int done, int total) { (*solving)(done, total); };
  hooks.resume = [&o, state_file, with_files](const nlohmann::json& identity) -> std::optional<SolverState> {
    if (!o.resume) {
      if (fs::exists(state_file))
        std::cout << "note: " << state_file.string()
                  << " holds the state of an interrupted run; this run starts afresh (--resume continues it)\n";
      return std::nullopt;
    }
    nlohmann::json saved_run;
    SolverState saved = read_solver_state(state_file, saved_run);
    require_same_run(saved_run, with_files(identity), state_file.string(), "run",
                     "continue with the same inputs and options, or start afresh without --resume");
    std::cout << "continuing " << saved.solver << " after iteration " << saved.iteration << " (state " << state_file.string()
              << ")\n";
    return saved;
  };
  hooks.checkpoint_every = o.checkpoint_every;
  hooks.save = [state_file, with_files](const SolverSnapshot& state, const nlohmann::json& identity) {
    write_solver_state(state, with_files(identity), state_file);
  };
  hooks.stop_requested = [] { return InterruptionWatch::requested(); };

  return hooks;
}

// The volume (slabs gathered from the ranks), its previews, the log and the page.
void write_outputs(const ReconstructionRun& run, const ReconstructOptions& o, const Geometry& geometry, const fs::path& log_file,
                   const fs::path& page, bool slabs, const Communicator& ranks) {
  if (slabs) {
    write_slabs(run.volume, run.plan.layout, ranks, o.out);
  } else {
    write_volume(run.volume, o.out);
    write_previews(run.volume, o.out);
  }
  nlohmann::json log = run.report();
  log["scan"] = o.scan.string();
  log["geometry"] = o.geometry.empty() ? geometry.origin : geometry.description();
  write_text_atomically(log_file, log.dump(2) + "\n");
  std::vector<fs::path> pictures = {preview_file(o.out, "_axial.png"), preview_file(o.out, "_coronal.png"),
                                    preview_file(o.out, "_sagittal.png")};
  if (write_convergence(run.solver.iterations, preview_file(o.out, "_convergence.png")))
    pictures.push_back(preview_file(o.out, "_convergence.png"));
  write_and_name_run_page("reconstruct", run.brief(), log, pictures, page);
}

void run_reconstruct(const ReconstructOptions& o) {
  const Communicator& ranks = world();
  const bool spread = ranks.size() > 1;
  const ScanDescription scan = read_scan_binned(o.scan, o.bin);
  RunFiles files;
  files.scan_to_read("--scan", o.scan, scan);
  files.input("--geometry", o.geometry);
  for (const fs::path& written : volume_files(o.out)) files.output("--out", written);
  const fs::path log_file = fs::path(o.out).replace_extension(".log.json");
  files.output("the log beside --out", log_file);
  const fs::path page = fs::path(o.out).replace_extension(".report.html");
  files.output("the HTML report beside --out", page);
  const fs::path state_file = fs::path(o.out).replace_extension(".state");
  files.output("the solver state beside --out", state_file);
  for (const char* slice : {"_axial.png", "_coronal.png", "_sagittal.png", "_convergence.png"})
    files.output(std::string("the preview beside --out"), preview_file(o.out, slice));
  files.check();
  OutputSet outputs;  // published together, after the last is written
  for (const auto& w : scan.warnings) std::cerr << "warning: " << w << "\n";
  const Geometry geometry = geometry_or_nominal(scan, o.scan, o.geometry);
  const ReconstructionOptions options = library_options(o);
  options.validate();
  say_which_views(scan, geometry, !o.geometry.empty());
  if (o.resume) require_state_to_continue(options.method, spread, state_file);

  Progress reading("reading projections", "views");
  std::optional<Progress> solving;
  // Spread over ranks, Ctrl-C ends the run at once (mpirun passes it to every rank): nothing is saved.
  std::optional<InterruptionWatch> watch;
  if (!spread) watch.emplace();
  const ReconstructionHooks hooks = console_hooks(o, spread, state_file, reading, solving);
  const ReconstructionRun run = run_reconstruction(scan, geometry, options, hooks, ranks);
  if (run.stopped() && options.method == ReconstructionMethod::os_sqs)
    throw Interrupted("stopped after epoch " + std::to_string(run.solver.iterations.back().iteration) +
                      "; OS-SQS keeps no state: nothing was written");
  if (run.stopped())
    throw Interrupted("stopped after iteration " + std::to_string(run.solver.iterations.back().iteration) +
                      "; the solver's state is in " + state_file.string() + ": run the same command with --resume to continue");
  if (run.circle)
    std::cout << "circular trajectory: radius " << run.circle->radius_mm << " mm, arc " << run.circle->arc_rad * 180 / M_PI
              << " deg" << (run.circle->arc_rad < 2 * M_PI - 1e-9 ? " (short scan: Parker weights)" : "") << "\n";
  std::cout << run.brief() << "\n";
  const bool slabs = spread && run.plan.distribution.decomposition == Decomposition::slabs;
  if (ranks.rank() != 0) {  // views split: every rank holds the volume, the first writes it
    if (slabs) ranks.send(0, std::span<const float>(run.volume.data.data(), run.volume.data.size()));
    return;
  }
  write_outputs(run, o, geometry, log_file, page, slabs, ranks);
  outputs.publish();
  std::error_code ignored;
  fs::remove(state_file, ignored);  // the run is complete: nothing left to continue
  std::cout << "volume written to " << o.out.string() << ", previews *_axial/_coronal/_sagittal.png (and _convergence), log "
            << log_file.string() << "\n";
}

}  // namespace

void register_reconstruct(CLI::App& app) {
  auto o = std::make_shared<ReconstructOptions>();
  CLI::App* cmd = app.add_subcommand("reconstruct", "Reconstruct a volume (holder frame) from a scan and its per-view matrices");
  cmd->add_option("--scan", o->scan, "scan.json (ctk-scan/1)")->required()->check(CLI::ExistingFile);
  cmd->add_option(
         "--bin", o->bin,
         "Bin the detector n x n (counts summed, pitch scaled); a --geometry made for the stored pixels is binned with it")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  cmd->add_option("--geometry", o->geometry, "Per-view matrices (ctk-geometry/1); default: the scan's nominal geometry")
      ->check(CLI::ExistingFile);
  cmd->add_option("--out", o->out,
                  "Volume to write, the format by extension: .nrrd, .mha (one file each), .mhd (+ .raw), .tif (float "
                  "pages, Fiji), .h5 (HDF5 dataset 'volume', z y x)")
      ->required()
      ->check(volume_file_name);
  cmd->add_option("--method", o->method,
                  "os-sqs (weighted least squares by ordered subsets with momentum); wls-cg (the same objective by "
                  "conjugate gradients, in more passes over the data, continued by --resume); sirt; fdk (circular scans only)")
      ->check(CLI::IsMember({"wls-cg", "os-sqs", "sirt", "fdk"}))
      ->capture_default_str();
  cmd->add_option("--iterations", o->run.iterations,
                  "Iterations on every view (default: until the views held out by --held-out-every stop fitting better, "
                  "at most 30 for wls-cg, 8 epochs for os-sqs, 100 for sirt)")
      ->check(CLI::Range(1, 100000));
  cmd->add_option("--held-out-every", o->run.held_out_every,
                  "Without --iterations: one view in n is held out of the solve, and the run stops with its best iterate "
                  "once their fit stops improving; 0 runs the default count on every view")
      ->check(CLI::Range(0, 100000))
      ->capture_default_str();
  cmd->add_option("--subsets", o->run.subsets, "os-sqs: ordered subsets (default: about 15 views each, at most 24)")
      ->check(CLI::Range(1, 100000));
  cmd->add_option("--lambda", o->run.lambda, "Regularisation weight")->check(non_negative_number)->capture_default_str();
  cmd->add_option("--regulariser", o->regulariser, "identity (Tikhonov) or gradient")
      ->check(CLI::IsMember({"identity", "gradient"}))
      ->capture_default_str();
  cmd->add_option("--huber-delta", o->run.huber_delta,
                  "os-sqs: an edge-preserving Huber penalty of neighbour differences (weight --lambda) instead of the "
                  "quadratic one; differences below delta (attenuation per mm) are smoothed, edges above it kept")
      ->check(positive_number);
  cmd->add_option("--preconditioner", o->preconditioner,
                  "wls-cg: none, or diagonal (the separable curvature A'WA1 + lambda c; one more projection pair and one "
                  "more volume)")
      ->check(CLI::IsMember({"none", "diagonal"}))
      ->capture_default_str();
  cmd->add_option("--tolerance", o->run.tolerance, "Stop when the gradient has fallen by this factor (0 <= tolerance < 1)")
      ->check(fraction_below_one)
      ->capture_default_str();
  cmd->add_flag("--unweighted", o->unweighted, "Unit weights even for counts (plain least squares)");
  cmd->add_flag("--as-measured", o->as_measured,
                "Use the images as measured even when the scan declares a detector distortion (by default they are "
                "resampled onto the matrices' pinhole grid)");
  cmd->add_option("--size", o->size, "Voxels: n (cube) or nx ny nz (default: cover the holder, or the field of view)")
      ->expected(1, 3)
      ->check(CLI::Range(1, 100000));
  cmd->add_option("--voxel", o->run.voxel_mm, "Voxel size in mm (default: a pixel seen at the holder origin)")
      ->check(positive_number);
  cmd->add_option("--decomposition", o->decomposition,
                  "Under mpirun: views (each rank its share of the views and the whole volume), slabs (each rank a slab of "
                  "the volume and the detector rows it owns; identity penalty only), or auto (views while they fit a rank)")
      ->check(CLI::IsMember({"auto", "views", "slabs"}))
      ->capture_default_str();
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

#include "ctk/recon/reconstruction_run.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <sstream>
#include <stdexcept>

#include "ctk/core/error.hpp"
#include "ctk/core/machine.hpp"
#include "ctk/core/provenance.hpp"
#include "ctk/core/statistics.hpp"
#include "ctk/proj/joseph_operator.hpp"
#include "ctk/proj/slab_split_operator.hpp"
#include "ctk/proj/view_split_operator.hpp"
#include "ctk/recon/default_volume.hpp"
#include "ctk/recon/held_out_fit.hpp"
#include "ctk/recon/ordered_subsets.hpp"
#include "ctk/recon/os_sqs.hpp"
#include "ctk/recon/sirt.hpp"
#include "ctk/recon/wls_cg.hpp"

namespace ctk {

namespace {

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

// What a saved state must match to be continued: the same data, views, volume and solver.
nlohmann::json run_identity(const ReconstructionPlan& plan, const ReconstructionOptions& o, const Measurements& m) {
  std::string data = std::to_string(fingerprint(m.line_integrals.data));
  if (plan.weighted) data.append("/").append(std::to_string(fingerprint(m.weights.data)));
  return {{"method", to_string(plan.method)},
          {"weights", plan.weighted ? "poisson" : "unit"},
          {"lambda", o.lambda},
          {"regulariser", to_string(o.regulariser)},
          {"huber_delta", o.huber_delta},
          {"tolerance", o.tolerance},
          {"preconditioner", to_string(o.preconditioner)},
          {"volume", {{"size", plan.layout.size}, {"voxel_mm", plan.layout.voxel_mm.x()}}},
          {"views_used", m.view_indices},
          {"data_fingerprint", data}};
}

// The whole run's views when each rank read its share: scan indices and matrices in the
// geometry's order, and where this rank holds each (-1: another rank).
struct SpreadViews {
  std::vector<int> indices;
  std::vector<ProjectionMatrix> matrices;
  std::vector<int> local;  // per position in `indices`: this rank's stack view, or -1
  /// This rank's stack views among `positions` (positions in `indices`), in their order.
  std::vector<int> local_positions(const std::vector<int>& positions) const {
    std::vector<int> out;
    for (int p : positions)
      if (const int k = local[static_cast<std::size_t>(p)]; k >= 0) out.push_back(k);
    return out;
  }
};

SpreadViews gather_views(const Geometry& geometry, const Measurements& m, const Communicator& ranks) {
  std::vector<int> used;
  for (const std::string& part : ranks.gather(nlohmann::json(m.view_indices).dump()))
    for (int v : nlohmann::json::parse(part)) used.push_back(v);
  SpreadViews out;
  for (int i : geometry.ok_views()) {
    const GeometryView& g = geometry.views[static_cast<std::size_t>(i)];
    if (std::find(used.begin(), used.end(), g.index) == used.end()) continue;
    out.indices.push_back(g.index);
    out.matrices.push_back(*g.P);
    const auto here = std::find(m.view_indices.begin(), m.view_indices.end(), g.index);
    out.local.push_back(here == m.view_indices.end() ? -1 : static_cast<int>(here - m.view_indices.begin()));
  }
  return out;
}

// Every rank's counts, views left out and notes, in rank order.
void combine_findings(const Measurements& m, const Communicator& ranks, Measurements& whole) {
  const nlohmann::json mine = {
      {"clamped", m.clamped_pixels}, {"masked", m.masked_pixels}, {"left_out", m.left_out}, {"notes", m.notes}};
  for (const std::string& part : ranks.gather(mine.dump())) {
    const nlohmann::json r = nlohmann::json::parse(part);
    whole.clamped_pixels += r["clamped"].get<std::size_t>();
    whole.masked_pixels += r["masked"].get<std::size_t>();
    for (const auto& s : r["left_out"]) whole.left_out.push_back(s.get<std::string>());
    for (const auto& s : r["notes"]) whole.notes.push_back(s.get<std::string>());
  }
}

// The operator a run solves with: the Joseph projector on the views read, split over the ranks as
// the plan says. Slabs: the split of every ok view, restricted to those read (a view left out
// keeps the others' rows where they were).
std::shared_ptr<const ProjectionOperator> spread_operator(const ReconstructionPlan& plan, const Geometry& geometry,
                                                          const Measurements& m, const Communicator& ranks, const Detector& d) {
  if (ranks.size() == 1 || plan.distribution.decomposition == Decomposition::views) {
    const auto local = std::make_shared<JosephOperator>(m.matrices, plan.layout, m.line_integrals.rows, m.line_integrals.cols);
    if (ranks.size() == 1) return local;
    return std::make_shared<ViewSplitOperator>(local, ranks);
  }
  std::vector<ProjectionMatrix> ok;
  std::vector<int> read;  // positions among the ok views of the views read
  for (int i : geometry.ok_views()) {
    const GeometryView& g = geometry.views[static_cast<std::size_t>(i)];
    if (std::find(m.view_indices.begin(), m.view_indices.end(), g.index) != m.view_indices.end())
      read.push_back(static_cast<int>(ok.size()));
    ok.push_back(*g.P);
  }
  const SlabSplitOperator all(ok, plan.layout, d.rows, d.cols, plan.distribution.rows, ranks);
  return all.subset(read);
}

void require_memory(const ReconstructionPlan& plan, bool spread) {
  if (plan.memory().total_bytes() > plan.available_bytes)
    throw std::runtime_error("the run needs " + plan.memory().describe() + (spread ? " per rank" : "") + " but only " +
                             std::to_string(static_cast<double>(plan.available_bytes) / 1e9) +
                             " GB are available: use a coarser voxel, a smaller volume or fewer views" +
                             (spread ? "" : ", or spread the views over more processes (mpirun)"));
}

// What this rank reads: in slabs every view, the rows it owns; views split, its share of the
// views, whole.
MeasurementOptions reading_options(const ReconstructionPlan& plan, const ReconstructionOptions& o, bool slabs,
                                   const Communicator& ranks) {
  MeasurementOptions reading;
  reading.statistical_weights = plan.weighted;
  reading.undistort = o.undistort;
  if (slabs) {
    const SlabRows& rows = *plan.distribution.rows;
    MeasurementOptions::RowWindow window;
    window.height = std::max(1, rows.owned_height(ranks.rank()));
    for (int k = 0; k < rows.views(); ++k) {
      window.first.push_back(rows.owned(k, ranks.rank()).first);
      window.count.push_back(rows.owned(k, ranks.rank()).count);
    }
    reading.rows = std::move(window);
  } else {
    reading.share = ranks.rank();
    reading.shares = ranks.size();
  }
  return reading;
}

// One view in `every`, spread over the directions, taken out of `m` to say when the image stops
// improving (every rank holds out the same views); none when there are too few views.
std::optional<HeldOutFit> hold_out_views(const ReconstructionPlan& plan, const Geometry& geometry, const Detector& detector,
                                         int every, const SpreadViews& views, bool views_split,
                                         const Eigen::Vector3d& volume_centre, const Communicator& ranks, Measurements& m) {
  const std::vector<int> chosen = held_out_positions(views.matrices, every, volume_centre);
  if (chosen.empty()) return std::nullopt;
  std::vector<int> here = views_split ? views.local_positions(chosen) : chosen;
  std::sort(here.begin(), here.end());
  std::vector<int> held_indices(chosen.size());
  std::transform(chosen.begin(), chosen.end(), held_indices.begin(),
                 [&](int p) { return views.indices[static_cast<std::size_t>(p)]; });
  Measurements held = take_views(m, here);
  return std::make_optional<HeldOutFit>(spread_operator(plan, geometry, held, ranks, detector), std::move(held.line_integrals),
                                        std::move(held.weights), std::move(held_indices),
                                        static_cast<std::size_t>(detector.rows) * static_cast<std::size_t>(detector.cols));
}

// One process's checkpoints: saved through the hooks under the run's identity, every
// `hooks.checkpoint_every` iterations and on a stop request; an earlier run's state (not for
// OS-SQS, which keeps none) into `saved`, for the solver to continue from.
Checkpointing checkpointing_for(const ReconstructionPlan& plan, const ReconstructionOptions& o, const Measurements& m,
                                const ReconstructionHooks& hooks, std::optional<SolverState>& saved) {
  Checkpointing checkpointing;
  const nlohmann::json identity = run_identity(plan, o, m);
  if (hooks.resume && plan.method != ReconstructionMethod::os_sqs) saved = hooks.resume(identity);
  checkpointing.save = [&hooks, identity](const SolverSnapshot& state) {
    if (hooks.save) hooks.save(state, identity);
  };
  checkpointing.every = hooks.checkpoint_every;
  checkpointing.stop_requested = hooks.stop_requested;
  checkpointing.resume = saved ? &*saved : nullptr;
  return checkpointing;
}

// The median of the steps of a growing count (bytes handed on per iteration).
std::size_t median_step(const std::vector<std::size_t>& counts) {
  std::vector<double> steps;
  for (std::size_t i = 1; i < counts.size(); ++i) steps.push_back(static_cast<double>(counts[i] - counts[i - 1]));
  return static_cast<std::size_t>(median_in_place(steps));
}

// What every iterative solver is called with beside its data.
struct SolverCall {
  const ProjectionOperator& A;
  const IterationCallback& on_iteration;
  Checkpointing* checkpointing;  // null: none (spread over ranks)
  const std::function<bool()>& stop_requested;
  StoppingRule stopping;
};

// The plan's iterative method on the views in `m` (OS-SQS's subsets over the whole run's views,
// each rank taking its views of every subset).
SolverReport solve(const ReconstructionPlan& plan, const ReconstructionOptions& o, const SolverCall& call, Measurements& m,
                   const SpreadViews& views, bool views_split, const Eigen::Vector3d& volume_centre, Volume& x) {
  const int iterations = o.iteration_count();
  const ProjectionStack* weights = plan.weighted ? &m.weights : nullptr;
  if (plan.method == ReconstructionMethod::os_sqs) {
    OsSqsOptions os;
    os.epochs = iterations;
    os.lambda = o.lambda;
    os.regulariser = o.regulariser;
    os.huber_delta = o.huber_delta;
    const int count = o.subsets > 0 ? o.subsets : default_subset_count(static_cast<int>(views.matrices.size()));
    std::vector<std::vector<int>> subsets = ordered_subsets(views.matrices, count, volume_centre);
    if (views_split)
      for (auto& subset : subsets) subset = views.local_positions(subset);
    return solve_os_sqs(call.A, m.line_integrals, weights, x, subsets, os, call.on_iteration, call.stop_requested, call.stopping);
  }
  if (plan.method == ReconstructionMethod::sirt)
    return solve_sirt(call.A, m.line_integrals, x, {iterations, 1.0, true}, call.on_iteration, call.checkpointing, call.stopping);
  WlsOptions w;
  w.iterations = iterations;
  w.tolerance = o.tolerance;
  w.lambda = o.lambda;
  w.regulariser = o.regulariser;
  w.preconditioner = o.preconditioner;
  return solve_wls_cg(call.A, m.line_integrals, weights, x, w, call.on_iteration, call.checkpointing, call.stopping);
}

}  // namespace

void ReconstructionOptions::validate() const {
  require_option(iterations >= 0, "ReconstructionOptions.iterations", "0 (the method's default) or more", iterations);
  require_option(huber_delta == 0 || (method == ReconstructionMethod::os_sqs && huber_delta > 0 && std::isfinite(huber_delta)),
                 "ReconstructionOptions.huber_delta", "0, or a finite positive number with the os-sqs method", huber_delta);
  require_choice(preconditioner == CgPreconditioner::none || method == ReconstructionMethod::wls_cg,
                 "ReconstructionOptions.preconditioner", "none unless the method is wls-cg", to_string(preconditioner));
  require_option(subsets >= 0, "ReconstructionOptions.subsets", "0 (chosen from the views) or more", subsets);
  require_option(held_out_every >= 0, "ReconstructionOptions.held_out_every", "0 (no views held out) or more", held_out_every);
  require_option(lambda >= 0 && std::isfinite(lambda), "ReconstructionOptions.lambda", "a finite number of 0 or more", lambda);
  require_option(tolerance >= 0 && tolerance < 1, "ReconstructionOptions.tolerance", "a number in [0, 1)", tolerance);
  for (int n : size) require_option(n >= 0, "ReconstructionOptions.size", "voxel counts of 0 (default) or more", n);
  require_option(voxel_mm >= 0 && std::isfinite(voxel_mm), "ReconstructionOptions.voxel_mm",
                 "a finite length of 0 (default) or more", voxel_mm);
}

bool ReconstructionOptions::stops_on_held_out_views() const {
  return iterations == 0 && held_out_every > 0 && method != ReconstructionMethod::fdk;
}

int ReconstructionOptions::iteration_count() const {
  if (iterations > 0) return iterations;
  switch (method) {
    case ReconstructionMethod::wls_cg:
      return 30;
    case ReconstructionMethod::os_sqs:
      return 8;
    case ReconstructionMethod::sirt:
      return 100;
    case ReconstructionMethod::fdk:
      return 0;
  }
  return 0;
}

int default_subset_count(int views) { return std::clamp((views + 7) / 15, 1, 24); }

bool ReconstructionRun::stopped() const {
  return solver.stop_reason == kStoppedOnRequest || solver.stop_reason == kStoppedWithoutState;
}

nlohmann::json ReconstructionRun::report() const {
  const VolumeLayout& l = plan.layout;
  nlohmann::json r = {
      {"format", "ctk-reconstruction-log/1"},
      {"provenance", provenance()},
      {"method", to_string(plan.method)},
      {"weights", plan.weighted ? "poisson" : "unit"},
      {"lambda", options.lambda},
      {"regulariser", options.huber_delta > 0 ? "huber" : to_string(options.regulariser)},
      {"huber_delta", options.huber_delta},
      {"preconditioner", to_string(options.preconditioner)},
      {"volume",
       {{"size", l.size}, {"voxel_mm", l.voxel_mm.x()}, {"origin_mm", {l.origin_mm.x(), l.origin_mm.y(), l.origin_mm.z()}}}},
      {"views_used", views_used},
      {"clamped_pixels", clamped_pixels},
      {"masked_pixels", masked_pixels},
      {"views_left_out", views_left_out},
      {"notes", notes},
      {"detector_distortion", distortion_note},
      {"memory_plan", plan.memory().describe()},
      {"solver", to_json(solver)},
      {"peak_resident_bytes_per_rank", peak_resident_bytes},
      {"seconds", seconds}};
  if (!held_out.is_null()) r["held_out"] = held_out;
  const DistributionPlan& d = plan.distribution;
  if (d.ranks > 1) {
    r["distribution"] = {{"ranks", d.ranks},
                         {"decomposition", to_string(d.decomposition)},
                         {"plans", d.describe()},
                         {"bytes_per_iteration", counted_bytes_per_iteration},
                         {"model_bytes_per_iteration", d.bytes_per_iteration()}};
    if (d.decomposition == Decomposition::slabs)
      r["distribution"]["planes_per_rank"] = d.planes_per_rank;
    else
      r["distribution"]["views_per_rank"] = d.views_per_rank;
  }
  if (circle) r["circular_trajectory"] = {{"radius_mm", circle->radius_mm}, {"arc_deg", circle->arc_rad * 180 / M_PI}};
  return r;
}

std::string ReconstructionRun::brief() const {
  std::ostringstream s;
  s << to_string(plan.method) << " on " << views_used.size() << " views, " << plan.layout.size[0] << " x " << plan.layout.size[1]
    << " x " << plan.layout.size[2] << " voxels: " << solver.stop_reason;
  if (plan.method != ReconstructionMethod::fdk && !solver.iterations.empty()) {
    // Stopped by held-out views, the volume is the iterate the rule returns: its cost, not the last's.
    const int kept = held_out.is_null() ? solver.iterations.back().iteration : held_out["result_iterations"].back().get<int>();
    const auto at = std::find_if(solver.iterations.begin(), solver.iterations.end(),
                                 [kept](const IterationLog& l) { return l.iteration == kept; });
    s << "; cost " << solver.iterations.front().cost << " -> "
      << (at != solver.iterations.end() ? *at : solver.iterations.back()).cost;
  }
  s << " (" << seconds << " s)";
  return s.str();
}

ReconstructionPlan plan_reconstruction(const ScanDescription& scan, const Geometry& geometry, const ReconstructionOptions& o,
                                       int ranks, int rank) {
  o.validate();
  ReconstructionPlan plan;
  plan.method = o.method;
  plan.weighted = (o.method == ReconstructionMethod::wls_cg || o.method == ReconstructionMethod::os_sqs) &&
                  o.statistical_weights && scan.projections.kind == ProjectionKind::counts;
  std::vector<ProjectionMatrix> ok;
  for (int i : geometry.ok_views()) ok.push_back(*geometry.views[static_cast<std::size_t>(i)].P);
  if (ok.empty()) throw InputError(geometry.source(), json_key("views"), "no view is \"ok\": nothing to reconstruct");
  plan.views = static_cast<int>(ok.size());
  // The layout needs the source distance: from the matrices, before any image.
  plan.layout = default_volume_layout(scan, ok, o.voxel_mm);
  if (std::any_of(o.size.begin(), o.size.end(), [](int n) { return n > 0; })) {
    std::array<int, 3> size = plan.layout.size;
    for (std::size_t a = 0; a < 3; ++a)
      if (o.size[a] > 0) size[a] = o.size[a];
    plan.layout = VolumeLayout::centred(size, plan.layout.voxel_mm);
  }
  plan.available_bytes = available_memory_bytes();
  const SolverShape solver{o.method,
                           o.lambda,
                           o.regulariser,
                           o.huber_delta,
                           plan.weighted,
                           o.preconditioner == CgPreconditioner::diagonal,
                           o.stops_on_held_out_views() ? o.held_out_every : 0};
  const int subsets = o.subsets > 0 ? o.subsets : default_subset_count(plan.views);
  plan.distribution = plan_distribution(solver, plan.layout, ok, scan.detector.rows, scan.detector.cols, subsets, ranks, rank,
                                        plan.available_bytes, o.decomposition);
  return plan;
}

// NOLINTNEXTLINE(readability-function-size): the workflow's steps in their order (plan, read, hold out, solve, report)
ReconstructionRun run_reconstruction(const ScanDescription& scan, const Geometry& geometry, const ReconstructionOptions& o,
                                     const ReconstructionHooks& hooks, const Communicator& ranks) {
  const auto start = std::chrono::steady_clock::now();
  const bool spread = ranks.size() > 1;
  ReconstructionRun run;
  run.options = o;
  run.plan = plan_reconstruction(scan, geometry, o, ranks.size(), ranks.rank());
  const ReconstructionPlan& plan = run.plan;
  const bool slabs = spread && plan.distribution.decomposition == Decomposition::slabs;
  if (hooks.planned) hooks.planned(plan);
  require_memory(plan, spread);

  Measurements m = load_measurements(scan, geometry, reading_options(plan, o, slabs, ranks), hooks.reading);
  // Views split, the run's views are every rank's, in the geometry's order; in slabs every rank
  // read them all (each its rows), and found the same in them.
  const bool views_split = spread && !slabs;
  const auto spread_views = [&] {
    return views_split ? gather_views(geometry, m, ranks) : SpreadViews{m.view_indices, m.matrices, {}};
  };
  SpreadViews views = spread_views();
  Measurements whole;  // views split, what the hooks and the report see: the whole run's numbers, no images
  if (views_split) {
    whole.view_indices = views.indices;
    whole.matrices = views.matrices;
    combine_findings(m, ranks, whole);
    whole.distortion_note = m.distortion_note;
  }
  const Measurements& found = views_split ? whole : m;
  if (hooks.measured) hooks.measured(found);
  require_views_left(found, geometry.source());
  run.clamped_pixels = found.clamped_pixels;
  run.masked_pixels = found.masked_pixels;
  run.views_left_out = found.left_out;
  run.notes = found.notes;
  run.distortion_note = m.distortion_note;

  const auto& n = plan.layout.size;
  const Eigen::Vector3d volume_centre =
      0.5 * (plan.layout.centre_of(0, 0, 0) + plan.layout.centre_of(n[0] - 1, n[1] - 1, n[2] - 1));
  std::optional<HeldOutFit> judge;  // default iterations: stopped where held-out views stop fitting better
  if (o.stops_on_held_out_views()) {
    judge = hold_out_views(plan, geometry, scan.detector, o.held_out_every, views, views_split, volume_centre, ranks, m);
    if (judge) views = spread_views();
    if (judge) judge->return_result(held_out_result(plan.method));
  }
  run.views_used = views.indices;

  run.volume = Volume(slabs ? slab_layout(plan.layout, ranks.rank(), ranks.size()) : plan.layout);
  const int iterations = o.iteration_count();
  std::vector<std::size_t> bytes_at;  // what this rank had handed to the others at each iteration
  const auto on_iteration = [&](const IterationLog& l) {
    bytes_at.push_back(ranks.bytes_sent());
    if (judge) judge->observe(l.iteration, run.volume);
    if (l.iteration > 0 && hooks.iterating) hooks.iterating(l.iteration, iterations);
  };
  if (plan.method == ReconstructionMethod::fdk) {
    // Refuses non-circular scans before any work, with the deviation found.
    run.circle = fit_circular_trajectory(m.matrices);
    fdk_reconstruct(m.matrices, m.line_integrals, scan.detector, run.volume);
    run.solver.stop_reason = "FDK (Hann-windowed ramp)";
    run.solver.iterations.push_back({});
  } else {
    // A state spread over ranks is not saved: checkpoints, continuing and stops are one process's.
    std::optional<SolverState> saved;  // OS-SQS keeps no state to continue
    Checkpointing checkpointing;
    if (!spread) checkpointing = checkpointing_for(plan, o, m, hooks, saved);
    const std::function<bool()> stop_requested = spread ? std::function<bool()>() : hooks.stop_requested;
    const std::shared_ptr<const ProjectionOperator> split = spread_operator(plan, geometry, m, ranks, scan.detector);
    const ProjectionOperator& A = *split;
    const SolverCall call{A, on_iteration, spread ? nullptr : &checkpointing, stop_requested,
                          judge ? judge->rule() : StoppingRule()};
    run.solver = solve(plan, o, call, m, views, views_split, volume_centre, run.volume);
    if (judge) {
      judge->restore_best(run.volume);
      run.held_out = judge->report();
    }
  }
  if (spread && bytes_at.size() > 1) run.counted_bytes_per_iteration = median_step(bytes_at);
  for (const std::string& peak : ranks.gather(std::to_string(peak_resident_bytes())))
    run.peak_resident_bytes.push_back(std::stoull(peak));
  run.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return run;
}

}  // namespace ctk

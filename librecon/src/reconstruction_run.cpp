#include "ctk/recon/reconstruction_run.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <sstream>
#include <stdexcept>

#include "ctk/core/error.hpp"
#include "ctk/proj/joseph_operator.hpp"
#include "ctk/recon/default_volume.hpp"
#include "ctk/recon/ordered_subsets.hpp"
#include "ctk/recon/os_sqs.hpp"
#include "ctk/recon/sirt.hpp"
#include "ctk/recon/wls_cg.hpp"
#include "ctk/core/provenance.hpp"

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
          {"volume", {{"size", plan.layout.size}, {"voxel_mm", plan.layout.voxel_mm.x()}}},
          {"views_used", m.view_indices},
          {"data_fingerprint", data}};
}

}  // namespace

void ReconstructionOptions::validate() const {
  require_option(iterations >= 0, "ReconstructionOptions.iterations", "0 (the method's default) or more", iterations);
  require_option(huber_delta == 0 || (method == ReconstructionMethod::os_sqs && huber_delta > 0 && std::isfinite(huber_delta)),
                 "ReconstructionOptions.huber_delta", "0, or a finite positive number with the os-sqs method", huber_delta);
  require_option(subsets >= 0, "ReconstructionOptions.subsets", "0 (chosen from the views) or more", subsets);
  require_option(lambda >= 0 && std::isfinite(lambda), "ReconstructionOptions.lambda", "a finite number of 0 or more", lambda);
  require_option(tolerance >= 0 && tolerance < 1, "ReconstructionOptions.tolerance", "a number in [0, 1)", tolerance);
  for (int n : size) require_option(n >= 0, "ReconstructionOptions.size", "voxel counts of 0 (default) or more", n);
  require_option(voxel_mm >= 0 && std::isfinite(voxel_mm), "ReconstructionOptions.voxel_mm",
                 "a finite length of 0 (default) or more", voxel_mm);
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
      {"volume",
       {{"size", l.size}, {"voxel_mm", l.voxel_mm.x()}, {"origin_mm", {l.origin_mm.x(), l.origin_mm.y(), l.origin_mm.z()}}}},
      {"views_used", views_used},
      {"clamped_pixels", clamped_pixels},
      {"masked_pixels", masked_pixels},
      {"views_left_out", views_left_out},
      {"notes", notes},
      {"detector_distortion", distortion_note},
      {"memory_plan", plan.memory.describe()},
      {"solver", to_json(solver)},
      {"seconds", seconds}};
  if (circle) r["circular_trajectory"] = {{"radius_mm", circle->radius_mm}, {"arc_deg", circle->arc_rad * 180 / M_PI}};
  return r;
}

std::string ReconstructionRun::brief() const {
  std::ostringstream s;
  s << to_string(plan.method) << " on " << views_used.size() << " views, " << plan.layout.size[0] << " x " << plan.layout.size[1]
    << " x " << plan.layout.size[2] << " voxels: " << solver.stop_reason;
  if (plan.method != ReconstructionMethod::fdk && !solver.iterations.empty())
    s << "; cost " << solver.iterations.front().cost << " -> " << solver.iterations.back().cost;
  s << " (" << seconds << " s)";
  return s.str();
}

ReconstructionPlan plan_reconstruction(const ScanDescription& scan, const Geometry& geometry, const ReconstructionOptions& o) {
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
  plan.memory = plan_memory(o.method, plan.layout, plan.views, scan.detector.rows, scan.detector.cols, plan.weighted);
  plan.available_bytes = available_memory_bytes();
  return plan;
}

ReconstructionRun run_reconstruction(const ScanDescription& scan, const Geometry& geometry, const ReconstructionOptions& o,
                                     const ReconstructionHooks& hooks) {
  const auto start = std::chrono::steady_clock::now();
  ReconstructionRun run;
  run.options = o;
  run.plan = plan_reconstruction(scan, geometry, o);
  const ReconstructionPlan& plan = run.plan;
  if (hooks.planned) hooks.planned(plan);
  if (plan.memory.total_bytes() > plan.available_bytes)
    throw std::runtime_error("the run needs " + plan.memory.describe() + " but only " +
                             std::to_string(static_cast<double>(plan.available_bytes) / 1e9) +
                             " GB are available: use a coarser voxel, a smaller volume or fewer views");

  MeasurementOptions reading;
  reading.statistical_weights = plan.weighted;
  reading.undistort = o.undistort;
  Measurements m = load_measurements(scan, geometry, reading, hooks.reading);
  if (hooks.measured) hooks.measured(m);
  require_views_left(m, geometry.source());
  run.views_used = m.view_indices;
  run.clamped_pixels = m.clamped_pixels;
  run.masked_pixels = m.masked_pixels;
  run.views_left_out = m.left_out;
  run.notes = m.notes;
  run.distortion_note = m.distortion_note;

  run.volume = Volume(plan.layout);
  const int iterations = o.iteration_count();
  const auto on_iteration = [&](const IterationLog& l) {
    if (l.iteration > 0 && hooks.iterating) hooks.iterating(l.iteration, iterations);
  };
  if (plan.method == ReconstructionMethod::fdk) {
    // Refuses non-circular scans before any work, with the deviation found.
    run.circle = fit_circular_trajectory(m.matrices);
    fdk_reconstruct(m.matrices, m.line_integrals, scan.detector, run.volume);
    run.solver.stop_reason = "FDK (Hann-windowed ramp)";
    run.solver.iterations.push_back({});
  } else {
    const nlohmann::json identity = run_identity(plan, o, m);
    std::optional<SolverState> saved;  // OS-SQS keeps no state to continue
    if (hooks.resume && plan.method != ReconstructionMethod::os_sqs) saved = hooks.resume(identity);
    Checkpointing checkpointing;
    checkpointing.resume = saved ? &*saved : nullptr;
    checkpointing.every = hooks.checkpoint_every;
    checkpointing.save = [&](const SolverSnapshot& state) {
      if (hooks.save) hooks.save(state, identity);
    };
    checkpointing.stop_requested = hooks.stop_requested;
    const JosephOperator A(m.matrices, plan.layout, m.line_integrals.rows, m.line_integrals.cols);
    if (plan.method == ReconstructionMethod::os_sqs) {
      OsSqsOptions os;
      os.epochs = iterations;
      os.lambda = o.lambda;
      os.regulariser = o.regulariser;
      os.huber_delta = o.huber_delta;
      const auto& n = plan.layout.size;
      const Eigen::Vector3d volume_centre =
          0.5 * (plan.layout.centre_of(0, 0, 0) + plan.layout.centre_of(n[0] - 1, n[1] - 1, n[2] - 1));
      const int count = o.subsets > 0 ? o.subsets : default_subset_count(static_cast<int>(m.matrices.size()));
      run.solver = solve_os_sqs(A, m.line_integrals, plan.weighted ? &m.weights : nullptr, run.volume,
                                ordered_subsets(m.matrices, count, volume_centre), os, on_iteration, hooks.stop_requested);
    } else if (plan.method == ReconstructionMethod::sirt) {
      run.solver = solve_sirt(A, m.line_integrals, run.volume, {iterations, 1.0, true}, on_iteration, &checkpointing);
    } else {
      WlsOptions w;
      w.iterations = iterations;
      w.tolerance = o.tolerance;
      w.lambda = o.lambda;
      w.regulariser = o.regulariser;
      run.solver =
          solve_wls_cg(A, m.line_integrals, plan.weighted ? &m.weights : nullptr, run.volume, w, on_iteration, &checkpointing);
    }
  }
  run.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return run;
}

}  // namespace ctk

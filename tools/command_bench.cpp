// ctk bench: throughput of the fast Joseph projector against the naive reference, measured in
// one run on the standard problem (see ctk/proj/standard_problem.hpp), as a table or JSON.
#include <chrono>
#include <cmath>
#include <iomanip>
#include <iostream>

#include "commands.hpp"
#include "ctk/proj/joseph_projector.hpp"
#include "ctk/proj/reference_projector.hpp"
#include "ctk/proj/standard_problem.hpp"

namespace ctk::tools {

namespace {

struct BenchOptions {
  int views = 360;
  int reference_views = 12;
  int scale = 1;
  int threads = 0;
  bool json = false;
};

template <typename F>
double seconds(F&& f) {
  const auto t0 = std::chrono::steady_clock::now();
  f();
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

double relative_difference(const std::vector<float>& a, const std::vector<float>& b) {
  double d = 0, n = 0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    d += (static_cast<double>(a[i]) - b[i]) * (static_cast<double>(a[i]) - b[i]);
    n += static_cast<double>(b[i]) * b[i];
  }
  return std::sqrt(d / std::max(n, 1e-300));
}

// One direction (forward or back) of one trajectory: fast on every view, reference on a subset,
// its time scaled per view to the full set (stated in the output).
nlohmann::json measure(const StandardProblem& p, const BenchOptions& o, bool forward, std::ostream& log) {
  const JosephProjector fast({o.threads, 8});
  const int n_views = static_cast<int>(p.views.size());
  const int n_ref = std::min(o.reference_views, n_views);
  std::vector<ProjectionMatrix> ref_views;
  for (int i = 0; i < n_ref; ++i) ref_views.push_back(p.views[static_cast<std::size_t>(i * n_views / n_ref)]);

  Volume x(p.layout);
  for (std::size_t i = 0; i < x.data.size(); ++i) x.data[i] = 0.5f + 0.5f * std::sin(0.001f * static_cast<float>(i));
  ProjectionStack y(n_views, p.rows, p.cols), y_ref(n_ref, p.rows, p.cols), y_fast_subset(n_ref, p.rows, p.cols);
  for (std::size_t i = 0; i < y.data.size(); ++i) y.data[i] = 1.0f + 0.5f * std::cos(0.01f * static_cast<float>(i));
  for (std::size_t i = 0; i < y_ref.data.size(); ++i) y_ref.data[i] = y.data[i];

  double fast_s = 0, ref_s = 0, agreement = 0;
  Volume out(p.layout), out_ref(p.layout), out_fast_subset(p.layout);
  if (forward) {
    fast_s = seconds([&] { fast.forward(x, p.views, y); });
    ref_s = seconds([&] { forward_project_reference(x, ref_views, y_ref); });
    fast.forward(x, ref_views, y_fast_subset);
    agreement = relative_difference(y_fast_subset.data, y_ref.data);
  } else {
    fast_s = seconds([&] { fast.back(y, p.views, out); });
    ref_s = seconds([&] { back_project_reference(y_ref, ref_views, out_ref); });
    fast.back(y_ref, ref_views, out_fast_subset);
    agreement = relative_difference(out_fast_subset.data, out_ref.data);
  }
  const double ref_full = ref_s * n_views / n_ref;
  const double voxel_views = static_cast<double>(p.layout.voxel_count()) * n_views;
  log << "  " << std::left << std::setw(8) << (forward ? "forward" : "back") << std::right << std::fixed
      << std::setprecision(3) << std::setw(10) << fast_s << " s" << std::setw(12) << ref_full << " s" << std::setw(9)
      << std::setprecision(1) << ref_full / fast_s << "x" << std::setw(12) << std::scientific << std::setprecision(2)
      << voxel_views / fast_s << std::setw(12) << voxel_views / ref_full << std::setw(11) << agreement << "\n";
  return {{"fast_seconds", fast_s},
          {"reference_seconds", ref_full},
          {"reference_seconds_measured", ref_s},
          {"reference_views_measured", n_ref},
          {"speedup", ref_full / fast_s},
          {"voxel_views_per_s", voxel_views / fast_s},
          {"reference_voxel_views_per_s", voxel_views / ref_full},
          {"relative_difference_to_reference", agreement}};
}

void run_bench(const BenchOptions& o) {
  std::ostream& log = o.json ? std::cerr : std::cout;
  const JosephProjector fast({o.threads, 8});
  nlohmann::json result;
  result["threads"] = fast.threads();
  result["simd"] = {{"target", JosephProjector::simd_target()}, {"float_lanes", JosephProjector::simd_lanes()}};
  for (const auto trajectory : {StandardTrajectory::circular, StandardTrajectory::spherical}) {
    const StandardProblem p = standard_problem(trajectory, o.views, o.scale);
    if (trajectory == StandardTrajectory::circular) {
      result["problem"] = {{"volume", p.layout.size},
                           {"voxel_mm", p.layout.voxel_mm.x()},
                           {"detector", {p.cols, p.rows}},
                           {"pixel_mm", 1.6 * o.scale},
                           {"source_isocentre_mm", 1000.0},
                           {"source_detector_mm", 1500.0},
                           {"views", o.views}};
    }
    log << p.trajectory << ": " << p.layout.size[0] << "^3 voxels, " << p.cols << " x " << p.rows << " detector, "
        << o.views << " views; fast on " << fast.threads() << " threads (" << JosephProjector::simd_target() << ", "
        << JosephProjector::simd_lanes() << " lanes), reference on 1 thread over " << std::min(o.reference_views, o.views)
        << " views scaled to " << o.views << "\n"
        << "  direction     fast   reference  speedup  fast vox-views/s  ref vox-views/s  rel.diff\n";
    nlohmann::json section = {{"forward", measure(p, o, true, log)}, {"back", measure(p, o, false, log)}};
    if (trajectory == StandardTrajectory::circular) {
      result["forward"] = section["forward"];
      result["back"] = section["back"];
    } else {
      result["spherical"] = section;
    }
  }
  if (o.json) std::cout << result.dump(2) << "\n";
}

}  // namespace

void register_bench(CLI::App& app) {
  auto options = std::make_shared<BenchOptions>();
  CLI::App* cmd = app.add_subcommand("bench", "Projector throughput: fast (all threads) vs naive reference (1 thread) on the standard problem");
  cmd->add_option("--views", options->views, "Views per trajectory")->capture_default_str()->check(CLI::Range(1, 100000));
  cmd->add_option("--reference-views", options->reference_views,
                  "Views the reference is timed on (its time is scaled per view to --views)")
      ->capture_default_str()->check(CLI::Range(1, 100000));
  cmd->add_option("--scale", options->scale, "Divide volume and detector sizes by this (1 = the standard problem)")
      ->capture_default_str()->check(CLI::Range(1, 64));
  cmd->add_option("--threads", options->threads, "Threads for the fast projector (0 = all)")->capture_default_str();
  cmd->add_flag("--json", options->json, "Print the result as JSON on stdout (the table goes to stderr)");
  cmd->callback([options] { run_bench(*options); });
}

}  // namespace ctk::tools

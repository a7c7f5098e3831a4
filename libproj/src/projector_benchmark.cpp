#include "ctk/proj/projector_benchmark.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <fstream>
#include <iomanip>
#include <sstream>

#include "ctk/core/atomic_write.hpp"
#include "ctk/core/error.hpp"
#include "ctk/core/machine.hpp"
#include "ctk/core/provenance.hpp"
#include "ctk/core/statistics.hpp"
#include "ctk/proj/joseph_projector.hpp"
#include "ctk/proj/reference_projector.hpp"
#include "ctk/proj/standard_problem.hpp"

namespace ctk {

namespace {

void say(const std::function<void(const std::string&)>& log, const std::string& line) {
  if (log) log(line);
}

// Raw float32, native byte order (little-endian on x86-64), as the manifest says.
void write_floats(const std::filesystem::path& file, const FloatBuffer& values) {
  write_file_atomically(file, [&](std::ostream& out) {
    out.write(reinterpret_cast<const char*>(values.data()), static_cast<std::streamsize>(values.size() * sizeof(float)));
  });
}

// The reference's views: n evenly spaced among the problem's.
std::vector<ProjectionMatrix> reference_subset(const StandardProblem& p, int n) {
  const int n_views = static_cast<int>(p.views.size());
  std::vector<ProjectionMatrix> subset;
  subset.reserve(static_cast<std::size_t>(n));
  for (int i = 0; i < n; ++i) subset.push_back(p.views[static_cast<std::size_t>(i * n_views / n)]);
  return subset;
}

// The views the back projection's bands need (a table of views that see the same voxels), which
// the reference's views, spread evenly, make only in part (circular views 180 degrees apart share
// voxels; spherical ones share too few): of the kDenseViews-view standard trajectory, the
// kNeighbours / 2 whose central rays lie nearest view 0's and as many nearest view kDenseViews / 4's
// (a quarter turn on the circle: rays along another axis of the volume, through its other bands).
constexpr int kDenseViews = 360, kNeighbours = 16;
std::vector<ProjectionMatrix> neighbouring_views(const StandardProblem& dense) {
  std::vector<ProjectionMatrix> chosen;
  for (const std::size_t centre : {std::size_t{0}, dense.views.size() / 4}) {
    const Eigen::Vector3d ray = dense.views[centre].principal_ray().normalized();
    std::vector<std::size_t> order(dense.views.size());
    for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
    const auto cosine = [&](std::size_t i) { return dense.views[i].principal_ray().normalized().dot(ray); };
    std::partial_sort(order.begin(), order.begin() + kNeighbours / 2, order.end(),
                      [&](std::size_t a, std::size_t b) { return cosine(a) > cosine(b); });
    for (int i = 0; i < kNeighbours / 2; ++i) chosen.push_back(dense.views[order[static_cast<std::size_t>(i)]]);
  }
  return chosen;
}

// What the yardstick reads: the layout, the detector, the subset's matrices and the raw files.
void write_dump_manifest(const StandardProblem& p, const std::vector<ProjectionMatrix>& views, const std::string& subset,
                         const std::filesystem::path& dir) {
  nlohmann::json matrices = nlohmann::json::array();
  for (const auto& P : views) {
    nlohmann::json rows = nlohmann::json::array();
    for (int r = 0; r < 3; ++r) rows.push_back({P.matrix()(r, 0), P.matrix()(r, 1), P.matrix()(r, 2), P.matrix()(r, 3)});
    matrices.push_back(rows);
  }
  const nlohmann::json j = {
      {"format", "ctk-bench-dump/1"},
      {"provenance", provenance()},
      {"trajectory", p.trajectory},
      {"subset", subset},
      {"volume",
       {{"size", p.layout.size},
        {"voxel_mm", {p.layout.voxel_mm.x(), p.layout.voxel_mm.y(), p.layout.voxel_mm.z()}},
        {"origin_mm", {p.layout.origin_mm.x(), p.layout.origin_mm.y(), p.layout.origin_mm.z()}},
        {"order", "x fastest"}}},
      {"detector", {{"cols", p.cols}, {"rows", p.rows}, {"pixel", "(u, v) = (column, row) at the pixel centre"}}},
      {"matrices", matrices},
      {"files", {{"x", "x.raw"}, {"y", "y.raw"}, {"forward", "forward.raw"}, {"back", "back.raw"}}},
      {"meaning", "forward = A x and back = A' y over these views, by the fast projector; float32, views x rows x cols"}};
  write_text_atomically(dir / "manifest.json", j.dump(2) + "\n");
}

// The benchmark's volume and projections: smooth, nonzero, the same on every run.
Volume bench_volume(const VolumeLayout& layout) {
  Volume x(layout);
  for (std::size_t i = 0; i < x.data.size(); ++i) x.data[i] = 0.5f + 0.5f * std::sin(0.001f * static_cast<float>(i));
  return x;
}
void fill_bench_projections(ProjectionStack& y) {
  for (std::size_t i = 0; i < y.data.size(); ++i) y.data[i] = 1.0f + 0.5f * std::cos(0.01f * static_cast<float>(i));
}

// The dump of the fast projector on neighbouring_views (a folder beside the trajectory's): A x and
// A' y there, which the yardstick checks as it checks the reference's views.
void dump_neighbours(StandardTrajectory trajectory, const ProjectorBenchmarkOptions& o) {
  const StandardProblem dense = standard_problem(trajectory, kDenseViews, o.scale);
  const std::vector<ProjectionMatrix> views = neighbouring_views(dense);
  const std::filesystem::path dir = o.dump / (dense.trajectory + "-neighbours");
  std::filesystem::create_directories(dir);
  const JosephProjector fast({o.threads});
  const Volume x = bench_volume(dense.layout);
  ProjectionStack y(static_cast<int>(views.size()), dense.rows, dense.cols), ax(y.views, y.rows, y.cols);
  fill_bench_projections(y);
  Volume aty(dense.layout);
  fast.forward(x, views, ax);
  fast.back(y, views, aty);
  write_floats(dir / "x.raw", x.data);
  write_floats(dir / "y.raw", y.data);
  write_floats(dir / "forward.raw", ax.data);
  write_floats(dir / "back.raw", aty.data);
  write_dump_manifest(dense, views, "neighbours: the views of the 360-view trajectory nearest views 0 and 90 in direction", dir);
}

template <typename F>
double seconds(F&& f) {
  const auto t0 = std::chrono::steady_clock::now();
  f();
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

double relative_difference(const FloatBuffer& a, const FloatBuffer& b) {
  double d = 0, n = 0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    d += (static_cast<double>(a[i]) - b[i]) * (static_cast<double>(a[i]) - b[i]);
    n += static_cast<double>(b[i]) * b[i];
  }
  return std::sqrt(d / std::max(n, 1e-300));
}

// One direction (forward or back) of one trajectory: fast on every view, reference on a subset,
// its time scaled per view to the full set (stated in the output).
nlohmann::json measure(const StandardProblem& p, const ProjectorBenchmarkOptions& o, bool forward,
                       const std::function<void(const std::string&)>& log) {
  const JosephProjector fast({o.threads});
  const int n_views = static_cast<int>(p.views.size());
  const int n_ref = std::min(o.reference_views, n_views);
  const std::vector<ProjectionMatrix> ref_views = reference_subset(p, n_ref);
  const std::filesystem::path dump = o.dump.empty() ? o.dump : o.dump / p.trajectory;

  const Volume x = bench_volume(p.layout);
  ProjectionStack y(n_views, p.rows, p.cols), y_ref(n_ref, p.rows, p.cols), y_fast_subset(n_ref, p.rows, p.cols);
  fill_bench_projections(y);
  fill_bench_projections(y_ref);

  double agreement = 0;
  std::vector<double> fast_runs, ref_runs;
  Volume out(p.layout), out_ref(p.layout), out_fast_subset(p.layout);
  // With --repeat the two take turns, a whole run each, and the medians count: a shared
  // machine's speed drifts by tens of percent within minutes. (Turns view by view were tried:
  // every reference view then started with a cold cache, which flattered the fast projector.)
  for (int run = 0; run < o.repeat; ++run) {
    fast_runs.push_back(seconds([&] { forward ? fast.forward(x, p.views, y) : fast.back(y, p.views, out); }));
    ref_runs.push_back(seconds(
        [&] { forward ? forward_project_reference(x, ref_views, y_ref) : back_project_reference(y_ref, ref_views, out_ref); }));
  }
  const double fast_s = median(fast_runs), ref_s = median(ref_runs);
  if (forward) {
    fast.forward(x, ref_views, y_fast_subset);
    agreement = relative_difference(y_fast_subset.data, y_ref.data);
    if (!dump.empty()) {
      write_floats(dump / "x.raw", x.data);
      write_floats(dump / "forward.raw", y_fast_subset.data);
    }
  } else {
    fast.back(y_ref, ref_views, out_fast_subset);
    agreement = relative_difference(out_fast_subset.data, out_ref.data);
    if (!dump.empty()) {
      write_floats(dump / "y.raw", y_ref.data);
      write_floats(dump / "back.raw", out_fast_subset.data);
    }
  }
  const double ref_full = ref_s * n_views / n_ref;
  const double voxel_views = static_cast<double>(p.layout.voxel_count()) * n_views;
  std::ostringstream line;
  line << "  " << std::left << std::setw(8) << (forward ? "forward" : "back") << std::right << std::fixed << std::setprecision(3)
       << std::setw(10) << fast_s << " s" << std::setw(12) << ref_full << " s" << std::setw(9) << std::setprecision(1)
       << ref_full / fast_s << "x" << std::setw(12) << std::scientific << std::setprecision(2) << voxel_views / fast_s
       << std::setw(12) << voxel_views / ref_full << std::setw(11) << agreement;
  say(log, line.str());
  nlohmann::json ref_runs_full = nlohmann::json::array();
  for (const double r : ref_runs) ref_runs_full.push_back(r * n_views / n_ref);
  return {{"fast_seconds", fast_s},
          {"fast_seconds_runs", fast_runs},
          {"reference_seconds_runs", ref_runs_full},
          {"reference_seconds", ref_full},
          {"reference_seconds_measured", ref_s},
          {"reference_views_measured", n_ref},
          {"speedup", ref_full / fast_s},
          {"voxel_views_per_s", voxel_views / fast_s},
          {"reference_voxel_views_per_s", voxel_views / ref_full},
          {"relative_difference_to_reference", agreement}};
}

}  // namespace

void ProjectorBenchmarkOptions::validate() const {
  require_option(views >= 1, "ProjectorBenchmarkOptions.views", "at least 1", views);
  require_option(reference_views >= 1, "ProjectorBenchmarkOptions.reference_views", "at least 1", reference_views);
  require_option(scale >= 1 && scale <= 64, "ProjectorBenchmarkOptions.scale", "1 to 64", scale);
  require_option(threads >= 0, "ProjectorBenchmarkOptions.threads", "0 (all) or more", threads);
  require_option(repeat >= 1, "ProjectorBenchmarkOptions.repeat", "at least 1", repeat);
  const std::vector<std::string> targets = JosephProjector::simd_targets();
  require_choice(simd.empty() || std::find(targets.begin(), targets.end(), simd) != targets.end(),
                 "ProjectorBenchmarkOptions.simd", "a SIMD target this build has (JosephProjector::simd_targets)", simd.c_str());
}

std::string ProjectorBenchmark::brief() const {
  std::ostringstream s;
  s << std::fixed << std::setprecision(1) << "circular forward " << report["forward"]["speedup"].get<double>() << "x, back "
    << report["back"]["speedup"].get<double>() << "x; spherical forward "
    << report["spherical"]["forward"]["speedup"].get<double>() << "x, back "
    << report["spherical"]["back"]["speedup"].get<double>() << "x the reference (fast on " << report["threads"].get<int>()
    << " threads, " << report["simd"]["target"].get<std::string>() << ")";
  return s.str();
}

ProjectorBenchmark run_projector_benchmark(const ProjectorBenchmarkOptions& o,
                                           const std::function<void(const std::string&)>& log) {
  o.validate();
  JosephProjector::use_simd_target(o.simd);
  const JosephProjector fast({o.threads});
  nlohmann::json result;
  result["threads"] = fast.threads();
  result["simd"] = {{"target", JosephProjector::simd_target()},
                    {"float_lanes", JosephProjector::simd_lanes()},
                    {"available", JosephProjector::simd_targets()}};
  result["cpu"] = cpu_identity();
  if (result["cpu"].contains("model_name"))
    say(log, "cpu: " + result["cpu"]["model_name"].get<std::string>() + " (family " +
                 std::to_string(result["cpu"].value("family", 0)) + ", model " + std::to_string(result["cpu"].value("model", 0)) +
                 ")");
  for (const auto trajectory : {StandardTrajectory::circular, StandardTrajectory::spherical}) {
    const StandardProblem p = standard_problem(trajectory, o.views, o.scale);
    if (!o.dump.empty()) {
      std::filesystem::create_directories(o.dump / p.trajectory);
      write_dump_manifest(p, reference_subset(p, std::min(o.reference_views, o.views)),
                          "reference: the views the reference ran on", o.dump / p.trajectory);
      dump_neighbours(trajectory, o);
    }
    if (trajectory == StandardTrajectory::circular) {
      result["problem"] = {{"volume", p.layout.size},   {"voxel_mm", p.layout.voxel_mm.x()}, {"detector", {p.cols, p.rows}},
                           {"pixel_mm", 1.6 * o.scale}, {"source_isocentre_mm", 1000.0},     {"source_detector_mm", 1500.0},
                           {"views", o.views}};
    }
    std::ostringstream head;
    head << p.trajectory << ": " << p.layout.size[0] << "^3 voxels, " << p.cols << " x " << p.rows << " detector, " << o.views
         << " views; fast on " << fast.threads() << " threads (" << JosephProjector::simd_target() << ", "
         << JosephProjector::simd_lanes() << " lanes), reference on 1 thread over " << std::min(o.reference_views, o.views)
         << " views scaled to " << o.views;
    if (o.repeat > 1) head << ", medians of " << o.repeat << " alternating runs";
    say(log, head.str());
    say(log, "  direction     fast   reference  speedup  fast vox-views/s  ref vox-views/s  rel.diff");
    nlohmann::json section = {{"forward", measure(p, o, true, log)}, {"back", measure(p, o, false, log)}};
    if (trajectory == StandardTrajectory::circular) {
      result["forward"] = section["forward"];
      result["back"] = section["back"];
    } else {
      result["spherical"] = section;
    }
  }
  return {result};
}

}  // namespace ctk

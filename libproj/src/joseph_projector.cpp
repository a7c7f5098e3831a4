#include "ctk/proj/joseph_projector.hpp"

#include <hwy/targets.h>
#include <omp.h>

#include <algorithm>
#include <array>
#include <cstdint>
#include <stdexcept>
#include <type_traits>

#include "ctk/core/cancellation.hpp"
#include "ctk/core/error.hpp"
#include "ray_table.hpp"
#include "slab_lines.hpp"

namespace ctk {

namespace {
// Rays per shared back-projection table (about 4.5 MB; there are two). With the views in slab
// order, a table of more views gathers more samples per band voxel: 65536 rather than 32768 made
// the spherical back projection 1.054x faster and the circular one 1.026x (49152: 1.032x,
// 98304: 1.036x spherical; in-process, benchmarks/paired.py).
constexpr int kBackTableRays = 65536;
}  // namespace

void ProjectorOptions::validate() const {
  // Each thread holds its own ray band (up to 1 MB): more threads than a few per processor buy
  // nothing and 100,000 of them ended the process.
  const int most = 4 * omp_get_num_procs();
  const std::string expected = "0 (all OpenMP threads) to " + std::to_string(most) + " (four per processor)";
  require_option(threads >= 0 && threads <= most, "ProjectorOptions.threads", expected.c_str(), threads);
  require_option(rows_per_block >= 0, "ProjectorOptions.rows_per_block", "at least 0 (0: the default for the views)",
                 rows_per_block);
}

JosephProjector::JosephProjector(ProjectorOptions options) : options_(options) { options_.validate(); }

// A chunk of slices (16 along x through tiles, 8 or 16 elsewhere) of a table's lines touches the
// rows of the lines plus the rows its rays drift across. Where the rays run within 0.2 voxel
// per slice of the rows (circular trajectories about an axis of the volume), 8 lines are best;
// where they cross rows faster (spherical trajectories), a taller table touches fewer rows per
// sample. The standard problem on the Zen 5 (benchmarks/paired.py): 24 lines made spherical views 1.06-1.16x
// faster each way and circular ones 0.94-0.99x forward (benchmarks/README.md).
int JosephProjector::default_rows_per_block(const std::vector<ProjectionMatrix>& views, const VolumeLayout& layout) {
  constexpr int kLinesAlongRows = 8;
  constexpr double kAcrossSlope = 0.2;  // voxels across rows per slice
  if (views.empty()) return kLinesAlongRows;
  std::vector<double> slopes;
  for (const ProjectionMatrix& P : views) {
    const Eigen::Vector3d d = P.principal_ray().cwiseAbs().cwiseQuotient(layout.voxel_mm);  // in voxels
    int a = 0;
    d.maxCoeff(&a);
    const int across = a == 2 ? 1 : 2;  // a slice's rows run along x (along y for rays along x)
    slopes.push_back(d[across] / d[a]);
  }
  const auto middle = slopes.begin() + static_cast<std::ptrdiff_t>(slopes.size() / 2);
  std::nth_element(slopes.begin(), middle, slopes.end());
  return *middle > kAcrossSlope ? detail::kLinesAcrossRows : kLinesAlongRows;
}

int JosephProjector::lines_per_table(const std::vector<ProjectionMatrix>& views, const VolumeLayout& layout) const {
  return options_.rows_per_block > 0 ? options_.rows_per_block : default_rows_per_block(views, layout);
}

int JosephProjector::threads() const { return options_.threads > 0 ? options_.threads : omp_get_max_threads(); }
std::string JosephProjector::simd_target() { return detail::simd_target_name(); }
int JosephProjector::simd_lanes() { return detail::simd_float_lanes(); }

namespace {
std::int64_t chosen_targets = 0;  // as Highway takes it: 0 for every target the CPU has

// What the binary has kernels for and the CPU runs, as Highway numbers them, widest first,
// whatever use_simd_target chose.
std::vector<std::int64_t> runnable_targets() {
  hwy::SetSupportedTargetsForTest(0);
  std::vector<std::int64_t> targets = hwy::SupportedAndGeneratedTargets();
  hwy::SetSupportedTargetsForTest(chosen_targets);
  return targets;
}
}  // namespace

std::vector<std::string> JosephProjector::simd_targets() {
  std::vector<std::string> names;
  for (const std::int64_t target : runnable_targets()) names.emplace_back(hwy::TargetName(target));
  return names;
}

void JosephProjector::use_simd_target(const std::string& target) {
  std::int64_t chosen = 0;
  for (const std::int64_t t : runnable_targets())
    if (target == hwy::TargetName(t)) chosen = t;
  if (chosen == 0 && !target.empty()) {
    std::string choices;
    for (const std::string& name : simd_targets()) choices += (choices.empty() ? "" : ", ") + name;
    throw std::invalid_argument("SIMD target '" + target + "': this binary on this CPU runs " + choices);
  }
  chosen_targets = chosen;
  hwy::SetSupportedTargetsForTest(chosen_targets);
}

namespace {

// Each view's rays and lane path, and its lines dealt into slabs (slab_lines.hpp).
struct ViewPaths {
  std::vector<ViewRays> rays;
  std::vector<detail::LanePath> path;
  detail::SlabLines dealt;
  int most_lanes = 0;
  ViewPaths(const std::vector<ProjectionMatrix>& views, const VolumeLayout& layout, int cols, int rows, int rows_per_block) {
    for (const auto& P : views) {
      rays.push_back(view_rays(P, layout));
      path.push_back(detail::LanePath::for_view(rays.back(), layout, cols, rows));
      most_lanes = std::max(most_lanes, path.back().majors);
    }
    dealt = detail::slab_lines(rays, path, layout, rows_per_block);
  }
};

// The detector pixel of table entry (row, lane) of lines from line_begin, or null outside it.
template <typename Stack>
auto pixel_of(const Stack& y, int v, const detail::LanePath& path, int line, int lane) -> decltype(y.view(v)) {
  if (!path.inside(line, lane)) return nullptr;
  int u, row;
  path.pixel(line, lane, u, row);
  return y.view(v) + static_cast<std::size_t>(row) * static_cast<std::size_t>(y.cols) + static_cast<std::size_t>(u);
}

}  // namespace

void JosephProjector::forward(ConstVolumeSpan x, const std::vector<ProjectionMatrix>& views, StackSpan y) const {
  check_stack_matches_views(y.views, y.rows, y.cols, views.size());
  const int rows_per_block = lines_per_table(views, x.layout);
  const ViewPaths paths(views, x.layout, y.cols, y.rows, rows_per_block);
  // Every view's lines of one slab, then the next slab's: neighbouring items read the same
  // voxels, which then stay in cache.
  std::vector<detail::LineRange> items;
  for (const auto& slab : paths.dealt.slabs) items.insert(items.end(), slab.begin(), slab.end());
  const int item_count = static_cast<int>(items.size());
#pragma omp parallel num_threads(threads())
  {
    // Pixels outside a view's footprint are in none of its lines: their rays miss the volume.
#pragma omp for schedule(static)
    for (int v = 0; v < y.views; ++v)
      if (!paths.path[static_cast<std::size_t>(v)].whole_detector) std::fill_n(y.view(v), y.pixels_per_view(), 0.0f);
    detail::RayTable table;
    table.shape(1, std::max(1, paths.dealt.capacity), paths.most_lanes);
    std::vector<float> out(table.pb_mid.size());
#pragma omp for schedule(dynamic, 1)
    for (int i = 0; i < item_count; ++i) {
      if (stop_requested()) continue;  // asked to stop from outside: the rest is skipped
      const detail::LineRange& item = items[static_cast<std::size_t>(i)];
      const int v = item.view;
      const auto& path = paths.path[static_cast<std::size_t>(v)];
      table.rows = item.lines;
      table.fill(paths.rays[static_cast<std::size_t>(v)], x.layout, 0, path, item.line_begin, 0, table.rows * table.row_stride);
      detail::forward_rays(table, x.data, out.data());
      for (int row = 0; row < table.rows; ++row)
        for (int lane = 0; lane < path.majors; ++lane)
          if (float* pixel = pixel_of(y, v, path, item.line_begin + row, lane)) *pixel = out[table.entry(0, row, lane)];
    }
  }
  throw_if_stop_requested();
}

namespace {

// One table's worth of the back projection: `views` of slab `slab`'s line ranges from v0.
struct BackBatch {
  int slab = 0, v0 = 0, views = 0;
};

// Samples (lane-slices) per dominant axis that one thread's fill tasks put in a table; summed
// over threads, they say which axes' slab tasks a table needs and in what order. Apart on their
// own cache lines: each thread adds to its own while the others add to theirs.
struct alignas(64) AxisSamples {
  std::array<std::int64_t, 3> of_table[2] = {};
};

// The first slice of slab s of `slabs` along `axis` (n slices). Along x, where slabs are at least
// a tile chunk wide, on multiples of kTileSlices, where the tiles' chunks start: an edge inside a
// chunk left two partial tiles, one per thread. Back projection with the edges moved, in-process
// (benchmarks/paired.py): 200^3 voxels (8 slabs of 25) 1.10x circular and 1.05x spherical, 300^3 1.07x and
// 1.04x; 256^3 had them there already. Narrower slabs keep their even edges: at 80^3, rounded
// edges left 5 slabs of 16 for 2 threads (0.96x).
int slab_edge(int s, int slabs, int n, int axis) {
  if (s >= slabs) return n;
  const int even = s * n / slabs;
  if (axis != 0 || n < slabs * detail::kTileSlices) return even;
  return std::min(n, (even + detail::kTileSlices / 2) / detail::kTileSlices * detail::kTileSlices);
}

// Table `buffer`'s samples per axis over every thread, and its axes fewest samples first.
struct TableAxes {
  std::array<std::int64_t, 3> samples{};
  std::array<int, 3> order{0, 1, 2};
};
TableAxes axes_fewest_first(const std::vector<AxisSamples>& samples, int buffer) {
  TableAxes t;
  for (const AxisSamples& s : samples)
    for (std::size_t a = 0; a < 3; ++a) t.samples[a] += s.of_table[buffer][a];
  std::stable_sort(t.order.begin(), t.order.end(),
                   [&](int p, int q) { return t.samples[static_cast<std::size_t>(p)] < t.samples[static_cast<std::size_t>(q)]; });
  return t;
}

}  // namespace

// NOLINTNEXTLINE(readability-function-size): the two tables and the region overlapping their fill stay together
void JosephProjector::back(ConstStackSpan y, const std::vector<ProjectionMatrix>& views, VolumeSpan x) const {
  check_stack_matches_views(y.views, y.rows, y.cols, views.size());
  std::fill_n(x.data, x.layout.voxel_count(), 0.0f);
  if (y.views == 0) return;
  const int rows_per_block = lines_per_table(views, x.layout);
  const ViewPaths paths(views, x.layout, y.cols, y.rows, rows_per_block);
  if (paths.dealt.capacity == 0) return;  // no view's footprint meets its detector
  const int n_threads = threads();
  const int capacity = paths.dealt.capacity;
  // Several views share one table, so the threads meet at a barrier once per batch rather than
  // once per view (barriers dominate small problems, and cost dearly when cores are shared).
  const int per_view = capacity * ((paths.most_lanes + detail::kMaxLanes - 1) / detail::kMaxLanes * detail::kMaxLanes);
  const int batch = std::clamp(kBackTableRays / per_view, 1, y.views);
  // Views innermost, as in forward(): a slab of the volume stays in cache across views.
  std::vector<BackBatch> batches;
  for (std::size_t slab = 0; slab < paths.dealt.slabs.size(); ++slab) {
    const int in_slab = static_cast<int>(paths.dealt.slabs[slab].size());
    for (int v0 = 0; v0 < in_slab; v0 += batch) batches.push_back({static_cast<int>(slab), v0, std::min(batch, in_slab - v0)});
  }
  // Two tables, shared by the threads: while the slab tasks read one, threads with no slab left
  // fill the other for the next batch instead of waiting at the barrier.
  std::array<detail::RayTable, 2> tables;
  for (detail::RayTable& table : tables) {
    table.shape(batch, capacity, paths.most_lanes);
    table.bundles.resize(detail::bundle_count(table));
  }
  std::vector<AxisSamples> samples(static_cast<std::size_t>(n_threads));
  const int lanes = detail::simd_float_lanes();
  const int count = capacity * tables[0].row_stride;  // entries per view
  // A view's entries are filled in n_threads parts of whole bundles, each prepared by its filler.
  const int part_size = ((count + n_threads - 1) / n_threads + detail::kMaxLanes - 1) / detail::kMaxLanes * detail::kMaxLanes;
  // Fill task `task` (of b.views * n_threads) of batch b into tables[buffer]: its part of one
  // view's rays, their projection values, their bundles, and their samples per axis.
  const auto fill = [&](const BackBatch& b, int buffer, int task) {
    detail::RayTable& table = tables[static_cast<std::size_t>(buffer)];
    const int slot = task / n_threads, part = task % n_threads;
    const detail::LineRange& lines = paths.dealt.slabs[static_cast<std::size_t>(b.slab)][static_cast<std::size_t>(b.v0 + slot)];
    const int v = lines.view;
    const auto& path = paths.path[static_cast<std::size_t>(v)];
    // Rows past this view's lines in the slab: rows of the shared table the kernels skip (slot_rows).
    const int rows = lines.lines;
    const int begin = std::min(count, part * part_size), filled = std::min(begin + part_size, rows * table.row_stride);
    const std::size_t first = table.entry(slot, 0, 0);
    table.fill(paths.rays[static_cast<std::size_t>(v)], x.layout, slot, path, lines.line_begin, begin, std::max(begin, filled));
    if (part == 0) table.slot_rows[static_cast<std::size_t>(slot)] = rows;
    if (task == 0) table.views = b.views;
    auto& on_axis = samples[static_cast<std::size_t>(omp_get_thread_num())].of_table[buffer];
    for (int r = begin; r < filled; ++r) {
      const int row = r / table.row_stride, lane = r % table.row_stride;
      const float* pixel = pixel_of(y, v, path, lines.line_begin + row, lane);
      const std::size_t e = first + static_cast<std::size_t>(r);
      table.value[e] = pixel ? *pixel : 0.0f;
      if (table.k_last[e] >= table.k_first[e])
        on_axis[static_cast<std::size_t>(table.axis[e])] += table.k_last[e] - table.k_first[e] + 1;
    }
    if (begin < filled)
      detail::prepare_bundles(table, (first + static_cast<std::size_t>(begin)) / static_cast<std::size_t>(lanes),
                              (first + static_cast<std::size_t>(filled)) / static_cast<std::size_t>(lanes));
  };
#pragma omp parallel num_threads(n_threads)
  {
#pragma omp for schedule(static)
    for (int task = 0; task < batches[0].views * n_threads; ++task) fill(batches[0], 0, task);
    for (std::size_t i = 0; i < batches.size(); ++i) {
      const int buffer = static_cast<int>(i % 2);
      const detail::RayTable& table = tables[static_cast<std::size_t>(buffer)];
      // This table's axes, fewest samples first; the last one's slab tasks share a loop with the
      // next table's fill tasks, which then take up the threads that would wait for the last slab.
      const TableAxes axes = axes_fewest_first(samples, buffer);
      const bool next = i + 1 < batches.size();
      const int fills = next ? batches[i + 1].views * n_threads : 0;
      auto& mine = samples[static_cast<std::size_t>(omp_get_thread_num())].of_table[1 - buffer];
      mine = {};  // read last for batch i - 1, before the barrier that ended it
      for (int o = 0; o < 3; ++o) {
        const int axis = axes.order[static_cast<std::size_t>(o)];
        const bool last = o == 2, busy = axes.samples[static_cast<std::size_t>(axis)] > 0;
        if (!busy && !last) continue;
        const int n = x.layout.size[static_cast<std::size_t>(axis)];
        // A sample at slice k writes only slice k of its dominant axis: slabs are disjoint.
        const int slabs = busy ? std::min(n, 4 * n_threads) : 0;
#pragma omp for schedule(dynamic, 1)
        for (int task = 0; task < slabs + (last ? fills : 0); ++task) {
          if (stop_requested()) continue;  // every thread still passes the barriers, doing nothing
          if (task < slabs)
            detail::back_rays(table, axis, slab_edge(task, slabs, n, axis), slab_edge(task + 1, slabs, n, axis), x.data);
          else
            fill(batches[i + 1], 1 - buffer, task - slabs);
        }
      }
    }
  }
  throw_if_stop_requested();
}

}  // namespace ctk

#include "ctk/proj/joseph_projector.hpp"

#include <omp.h>

#include <algorithm>
#include <stdexcept>

#include "ray_table.hpp"

namespace ctk {

namespace {
constexpr int kBackTableRays = 32768;  // rays per shared back-projection table (~2 MB)
}  // namespace

JosephProjector::JosephProjector(ProjectorOptions options) : options_(options) {
  if (options_.rows_per_block <= 0) throw std::invalid_argument("ProjectorOptions: rows_per_block must be positive");
}

int JosephProjector::threads() const { return options_.threads > 0 ? options_.threads : omp_get_max_threads(); }
std::string JosephProjector::simd_target() { return detail::simd_target_name(); }
int JosephProjector::simd_lanes() { return detail::simd_float_lanes(); }

void JosephProjector::forward(const Volume& x, const std::vector<ProjectionMatrix>& views, ProjectionStack& y) const {
  check_stack_matches_views(y, views.size());
  const int rows_per_block = std::min(options_.rows_per_block, y.rows);
  const int blocks = (y.rows + rows_per_block - 1) / rows_per_block;
  const int items = y.views * blocks;
#pragma omp parallel num_threads(threads())
  {
    detail::RayTable table;
    table.shape(1, rows_per_block, y.cols);
    std::vector<float> out(table.pb_mid.size());
#pragma omp for schedule(dynamic, 1)
    for (int item = 0; item < items; ++item) {
      // Views vary fastest: the same detector rows of neighbouring views see nearly the same
      // band of the volume, which then stays in cache.
      const int v = item % y.views, row_begin = (item / y.views) * rows_per_block;
      table.rows = std::min(rows_per_block, y.rows - row_begin);
      table.fill(view_rays(views[static_cast<std::size_t>(v)], x.layout), x.layout, 0, row_begin, y.cols, 0,
                 table.rows * y.cols);
      detail::forward_rays(table, x.data.data(), out.data());
      for (int row = 0; row < table.rows; ++row)
        std::copy_n(out.begin() + static_cast<std::ptrdiff_t>(table.entry(0, row, 0)), y.cols,
                    y.view(v) + static_cast<std::size_t>(row_begin + row) * static_cast<std::size_t>(y.cols));
    }
  }
}

void JosephProjector::back(const ProjectionStack& y, const std::vector<ProjectionMatrix>& views, Volume& x) const {
  check_stack_matches_views(y, views.size());
  std::fill(x.data.begin(), x.data.end(), 0.0f);
  if (y.views == 0) return;
  const int rows_per_block = std::min(options_.rows_per_block, y.rows);
  const int blocks = (y.rows + rows_per_block - 1) / rows_per_block;
  const int n_threads = threads();
  // Several views share one table, so the threads meet at a barrier once per batch rather than
  // once per view (barriers dominate small problems, and cost dearly when cores are shared).
  const int per_view = rows_per_block * ((y.cols + detail::kMaxLanes - 1) / detail::kMaxLanes * detail::kMaxLanes);
  const int batch = std::clamp(kBackTableRays / per_view, 1, y.views);
  detail::RayTable table;  // shared: filled together, then read by every slab task
  table.shape(batch, rows_per_block, y.cols);
  table.bundles.resize(detail::bundle_count(table));
#pragma omp parallel num_threads(n_threads)
  {
    // Views innermost, as in forward(): a band of the volume stays in cache across views.
    for (int block = 0; block < blocks; ++block) {
      const int row_begin = block * rows_per_block;
      const int rows = std::min(rows_per_block, y.rows - row_begin);
      const int count = rows * y.cols;
      const int chunk = (count + n_threads - 1) / n_threads;
      for (int v0 = 0; v0 < y.views; v0 += batch) {
        const int in_batch = std::min(batch, y.views - v0);
#pragma omp for schedule(static)
        for (int task = 0; task < in_batch * n_threads; ++task) {
          const int slot = task / n_threads, part = task % n_threads, v = v0 + slot;
          const int begin = std::min(count, part * chunk), end = std::min(count, begin + chunk);
          table.fill(view_rays(views[static_cast<std::size_t>(v)], x.layout), x.layout, slot, row_begin, y.cols, begin,
                     end);
          const float* values = y.view(v) + static_cast<std::size_t>(row_begin) * static_cast<std::size_t>(y.cols);
          for (int r = begin; r < end; ++r) table.value[table.entry(slot, r / y.cols, r % y.cols)] = values[r];
          if (task == 0) {
            table.views = in_batch;
            table.rows = rows;
          }
        }
        // Each bundle once for every slab task that marches it.
        const auto bundles_in_use = static_cast<std::size_t>(in_batch) * table.bundles.size() / static_cast<std::size_t>(batch);
#pragma omp for schedule(static)
        for (int part = 0; part < n_threads; ++part)
          detail::prepare_bundles(table, bundles_in_use * static_cast<std::size_t>(part) / static_cast<std::size_t>(n_threads),
                                  bundles_in_use * static_cast<std::size_t>(part + 1) / static_cast<std::size_t>(n_threads));
        // A sample at slice k writes only slice k of its dominant axis: slabs are disjoint.
        for (int axis = 0; axis < 3; ++axis) {
          const int n = x.layout.size[static_cast<std::size_t>(axis)];
          const int slabs = std::min(n, 4 * n_threads);
#pragma omp for schedule(dynamic, 1)
          for (int s = 0; s < slabs; ++s)
            detail::back_rays(table, axis, s * n / slabs, (s + 1) * n / slabs, x.data.data());
        }
      }
    }
  }
}

}  // namespace ctk

#include "ctk/proj/arc_averaged_projection.hpp"

#include <algorithm>
#include <cstddef>
#include <stdexcept>
#include <string>
#include <utility>

namespace ctk {

namespace {

std::vector<ProjectionMatrix> flattened(const std::vector<std::vector<ProjectionMatrix>>& sub_views) {
  std::vector<ProjectionMatrix> all;
  for (std::size_t v = 0; v < sub_views.size(); ++v) {
    if (sub_views[v].empty())
      throw std::invalid_argument("ArcAveragedProjection: view " + std::to_string(v) + " has no sub-views");
    all.insert(all.end(), sub_views[v].begin(), sub_views[v].end());
  }
  return all;
}

}  // namespace

ArcAveragedProjection::ArcAveragedProjection(std::vector<std::vector<ProjectionMatrix>> sub_views, const VolumeLayout& layout,
                                             int rows, int cols, const ProjectorOptions& options)
    : sub_views_(std::move(sub_views)), all_(flattened(sub_views_), layout, rows, cols, options), options_(options) {
  int first = 0;
  for (const auto& s : sub_views_) {
    first_.push_back(first);
    first += static_cast<int>(s.size());
  }
}

std::shared_ptr<const ProjectionOperator> ArcAveragedProjection::subset(const std::vector<int>& views) const {
  check_subset(views);
  std::vector<std::vector<ProjectionMatrix>> chosen;
  chosen.reserve(views.size());
  for (int v : views) chosen.push_back(sub_views_[static_cast<std::size_t>(v)]);
  const StackShape s = range();
  return std::make_shared<ArcAveragedProjection>(std::move(chosen), domain(), s.rows, s.cols, options_);
}

void ArcAveragedProjection::do_apply(ConstVolumeSpan x, StackSpan y) const {
  ProjectionStack sub;
  all_.apply(x, sub);
  const std::size_t pixels = y.pixels_per_view();
  const std::ptrdiff_t views = y.views;
#pragma omp parallel for schedule(static)
  for (std::ptrdiff_t v = 0; v < views; ++v) {
    const std::size_t n = sub_views_[static_cast<std::size_t>(v)].size();
    const float scale = 1.0f / static_cast<float>(n);
    float* out = y.view(static_cast<int>(v));
    std::fill(out, out + pixels, 0.0f);
    for (std::size_t s = 0; s < n; ++s) {
      const float* in = sub.view(first_[static_cast<std::size_t>(v)] + static_cast<int>(s));
      for (std::size_t p = 0; p < pixels; ++p) out[p] += scale * in[p];
    }
  }
}

void ArcAveragedProjection::do_apply_adjoint(ConstStackSpan y, VolumeSpan x) const {
  ProjectionStack sub = all_.range_zeros();
  const std::size_t pixels = y.pixels_per_view();
  const std::ptrdiff_t views = y.views;
#pragma omp parallel for schedule(static)
  for (std::ptrdiff_t v = 0; v < views; ++v) {
    const std::size_t n = sub_views_[static_cast<std::size_t>(v)].size();
    const float scale = 1.0f / static_cast<float>(n);
    const float* in = y.view(static_cast<int>(v));
    for (std::size_t s = 0; s < n; ++s) {
      float* out = sub.view(first_[static_cast<std::size_t>(v)] + static_cast<int>(s));
      for (std::size_t p = 0; p < pixels; ++p) out[p] = scale * in[p];
    }
  }
  all_.apply_adjoint(sub, x);
}

}  // namespace ctk

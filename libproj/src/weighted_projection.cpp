#include "ctk/proj/weighted_projection.hpp"

#include <algorithm>
#include <cstddef>
#include <stdexcept>
#include <utility>

namespace ctk {

namespace {

// out = factors * in, pixel by pixel (out may be in).
void multiply(const ProjectionStack& factors, const float* in, float* out) {
  const std::ptrdiff_t n = static_cast<std::ptrdiff_t>(factors.data.size());
#pragma omp parallel for schedule(static)
  for (std::ptrdiff_t i = 0; i < n; ++i) {
    const std::size_t k = static_cast<std::size_t>(i);
    out[k] = factors.data[k] * in[k];
  }
}

}  // namespace

WeightedProjection::WeightedProjection(std::shared_ptr<const ProjectionOperator> inner, ProjectionStack factors)
    : inner_(std::move(inner)), factors_(std::move(factors)) {
  if (!inner_) throw std::invalid_argument("WeightedProjection: no inner operator");
  const StackShape r = inner_->range();
  if (!(StackShape::of(factors_) == r) || factors_.data.size() != static_cast<std::size_t>(r.views) *
                                                                      static_cast<std::size_t>(r.rows) *
                                                                      static_cast<std::size_t>(r.cols))
    throw std::invalid_argument("WeightedProjection: the factors do not have the shape of the operator's projections");
}

std::shared_ptr<const ProjectionOperator> WeightedProjection::subset(const std::vector<int>& views) const {
  check_subset(views);
  ProjectionStack chosen(static_cast<int>(views.size()), factors_.rows, factors_.cols);
  for (std::size_t i = 0; i < views.size(); ++i) {
    const float* from = factors_.view(views[i]);
    std::copy(from, from + factors_.pixels_per_view(), chosen.view(static_cast<int>(i)));
  }
  return std::make_shared<WeightedProjection>(inner_->subset(views), std::move(chosen));
}

void WeightedProjection::do_apply(ConstVolumeSpan x, StackSpan y) const {
  inner_->apply(x, y);
  multiply(factors_, y.data, y.data);
}

void WeightedProjection::do_apply_adjoint(ConstStackSpan y, VolumeSpan x) const {
  ProjectionStack weighted(y.views, y.rows, y.cols);
  multiply(factors_, y.data, weighted.data.data());
  inner_->apply_adjoint(weighted, x);
}

}  // namespace ctk

#include "ctk/proj/binned_projection.hpp"

#include <cstddef>
#include <stdexcept>
#include <string>
#include <utility>

namespace ctk {

BinnedProjection::BinnedProjection(std::shared_ptr<const ProjectionOperator> inner, int factor)
    : inner_(std::move(inner)), factor_(factor) {
  if (!inner_) throw std::invalid_argument("BinnedProjection: no inner operator");
  const StackShape s = inner_->range();
  if (factor < 1 || factor > s.rows || factor > s.cols)
    throw std::invalid_argument("BinnedProjection: binning factor " + std::to_string(factor) + " does not fit a " +
                                std::to_string(s.cols) + " x " + std::to_string(s.rows) + " detector");
}

StackShape BinnedProjection::range() const {
  const StackShape s = inner_->range();
  return {s.views, s.rows / factor_, s.cols / factor_};
}

std::shared_ptr<const ProjectionOperator> BinnedProjection::subset(const std::vector<int>& views) const {
  return std::make_shared<BinnedProjection>(inner_->subset(views), factor_);
}

void BinnedProjection::do_apply(ConstVolumeSpan x, StackSpan y) const {
  ProjectionStack fine;
  inner_->apply(x, fine);
  const int b = factor_;
  const float scale = 1.0f / static_cast<float>(b * b);
  const std::ptrdiff_t views = y.views;
#pragma omp parallel for schedule(static)
  for (std::ptrdiff_t v = 0; v < views; ++v) {
    const float* in = fine.view(static_cast<int>(v));
    float* out = y.view(static_cast<int>(v));
    for (int r = 0; r < y.rows; ++r)
      for (int c = 0; c < y.cols; ++c) {
        float sum = 0;
        for (int i = 0; i < b; ++i)
          for (int j = 0; j < b; ++j)
            sum += in[static_cast<std::size_t>(r * b + i) * static_cast<std::size_t>(fine.cols) +
                      static_cast<std::size_t>(c * b + j)];
        out[static_cast<std::size_t>(r) * static_cast<std::size_t>(y.cols) + static_cast<std::size_t>(c)] = scale * sum;
      }
  }
}

void BinnedProjection::do_apply_adjoint(ConstStackSpan y, VolumeSpan x) const {
  ProjectionStack fine = inner_->range_zeros();  // the dropped partial rows and columns stay zero
  const int b = factor_;
  const float scale = 1.0f / static_cast<float>(b * b);
  const std::ptrdiff_t views = y.views;
#pragma omp parallel for schedule(static)
  for (std::ptrdiff_t v = 0; v < views; ++v) {
    const float* in = y.view(static_cast<int>(v));
    float* out = fine.view(static_cast<int>(v));
    for (int r = 0; r < y.rows * b; ++r)
      for (int c = 0; c < y.cols * b; ++c)
        out[static_cast<std::size_t>(r) * static_cast<std::size_t>(fine.cols) + static_cast<std::size_t>(c)] =
            scale * in[static_cast<std::size_t>(r / b) * static_cast<std::size_t>(y.cols) + static_cast<std::size_t>(c / b)];
  }
  inner_->apply_adjoint(fine, x);
}

}  // namespace ctk

#pragma once
// A detector read out in b x b blocks: B A, with B the mean of each block (a last partial row or
// column dropped) and B' spreading each binned value over its block divided by b^2, so the pair
// stays adjoint. Unlike binned matrices (detector_binning.hpp: one ray per coarse pixel, b^2 times
// cheaper), this integrates every fine ray of a block, as a binning detector does.
#include <memory>

#include "ctk/proj/projection_operator.hpp"

namespace ctk {

class BinnedProjection final : public ProjectionOperator {
 public:
  /// Throws std::invalid_argument for a factor below 1 or larger than the inner detector.
  BinnedProjection(std::shared_ptr<const ProjectionOperator> inner, int factor);

  const VolumeLayout& domain() const override { return inner_->domain(); }
  StackShape range() const override;
  std::shared_ptr<const ProjectionOperator> subset(const std::vector<int>& views) const override;
  double sum_over_range(double part) const override { return inner_->sum_over_range(part); }
  double sum_over_domain(double part) const override { return inner_->sum_over_domain(part); }
  int factor() const { return factor_; }

 private:
  void do_apply(ConstVolumeSpan x, StackSpan y) const override;
  void do_apply_adjoint(ConstStackSpan y, VolumeSpan x) const override;

  std::shared_ptr<const ProjectionOperator> inner_;
  int factor_;
};

}  // namespace ctk

#pragma once
// D A with D a fixed per-pixel factor (a detector mask, a gain, or the square roots of
// statistical weights, which turns a weighted problem into an unweighted one). D is diagonal, so
// the adjoint is A' D.
#include <memory>

#include "ctk/proj/projection_operator.hpp"

namespace ctk {

class WeightedProjection final : public ProjectionOperator {
 public:
  /// Throws std::invalid_argument when `factors` does not have the inner operator's range shape.
  WeightedProjection(std::shared_ptr<const ProjectionOperator> inner, ProjectionStack factors);

  const VolumeLayout& domain() const override { return inner_->domain(); }
  StackShape range() const override { return inner_->range(); }
  std::shared_ptr<const ProjectionOperator> subset(const std::vector<int>& views) const override;
  double sum_over_range(double part) const override { return inner_->sum_over_range(part); }
  double sum_over_domain(double part) const override { return inner_->sum_over_domain(part); }
  const ProjectionStack& factors() const { return factors_; }

 private:
  void do_apply(ConstVolumeSpan x, StackSpan y) const override;
  void do_apply_adjoint(ConstStackSpan y, VolumeSpan x) const override;

  std::shared_ptr<const ProjectionOperator> inner_;
  ProjectionStack factors_;
};

}  // namespace ctk

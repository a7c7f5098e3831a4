#pragma once
// Views that integrate while the sample moves: each view is the mean of the projections through
// its sub-views (matrices sampled along the arc the sample travels during the exposure). The
// operator projects every sub-view with the Joseph projector and averages each view's; its
// adjoint spreads each view's value to its sub-views divided by their number.
#include <memory>
#include <vector>

#include "ctk/geom/projection_matrix.hpp"
#include "ctk/proj/joseph_operator.hpp"

namespace ctk {

class ArcAveragedProjection final : public ProjectionOperator {
 public:
  /// sub_views[v]: the matrices whose projections view v averages (at least one per view).
  /// Throws std::invalid_argument for a view without sub-views.
  ArcAveragedProjection(std::vector<std::vector<ProjectionMatrix>> sub_views, const VolumeLayout& layout, int rows, int cols,
                        const ProjectorOptions& options = {});

  const VolumeLayout& domain() const override { return all_.domain(); }
  StackShape range() const override { return {static_cast<int>(sub_views_.size()), all_.range().rows, all_.range().cols}; }
  std::shared_ptr<const ProjectionOperator> subset(const std::vector<int>& views) const override;

 private:
  void do_apply(ConstVolumeSpan x, StackSpan y) const override;
  void do_apply_adjoint(ConstStackSpan y, VolumeSpan x) const override;

  std::vector<std::vector<ProjectionMatrix>> sub_views_;
  std::vector<int> first_;  // index of view v's first sub-view in all_
  JosephOperator all_;      // every sub-view, view by view
  ProjectorOptions options_;
};

}  // namespace ctk

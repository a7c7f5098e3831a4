#pragma once
// The Joseph projector on a set of views (3x4 matrices), a volume layout and a detector size: the
// operator every reconstruction starts from. A subset of its views is the same projector on those
// views' matrices, so subsets cost nothing.
#include <memory>
#include <vector>

#include "ctk/geom/projection_matrix.hpp"
#include "ctk/proj/joseph_projector.hpp"
#include "ctk/proj/projection_operator.hpp"

namespace ctk {

class JosephOperator final : public ProjectionOperator {
 public:
  /// Throws std::invalid_argument for an empty layout or a detector without pixels.
  JosephOperator(std::vector<ProjectionMatrix> views, const VolumeLayout& layout, int rows, int cols,
                 const ProjectorOptions& options = {});

  const VolumeLayout& domain() const override { return layout_; }
  StackShape range() const override { return {static_cast<int>(views_.size()), rows_, cols_}; }
  std::shared_ptr<const ProjectionOperator> subset(const std::vector<int>& views) const override;

  const std::vector<ProjectionMatrix>& views() const { return views_; }
  const JosephProjector& projector() const { return projector_; }

 private:
  void do_apply(ConstVolumeSpan x, StackSpan y) const override;
  void do_apply_adjoint(ConstStackSpan y, VolumeSpan x) const override;

  std::vector<ProjectionMatrix> views_;
  VolumeLayout layout_;
  int rows_, cols_;
  ProjectorOptions options_;
  JosephProjector projector_;
};

}  // namespace ctk

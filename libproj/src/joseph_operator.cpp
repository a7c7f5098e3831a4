#include "ctk/proj/joseph_operator.hpp"

#include <stdexcept>
#include <utility>

namespace ctk {

JosephOperator::JosephOperator(std::vector<ProjectionMatrix> views, const VolumeLayout& layout, int rows, int cols,
                               const ProjectorOptions& options)
    : views_(std::move(views)), layout_(layout), rows_(rows), cols_(cols), options_(options), projector_(options) {
  if (layout.voxel_count() == 0) throw std::invalid_argument("JosephOperator: the volume layout has no voxels");
  if (rows < 1 || cols < 1) throw std::invalid_argument("JosephOperator: the detector has no pixels");
}

std::shared_ptr<const ProjectionOperator> JosephOperator::subset(const std::vector<int>& views) const {
  check_subset(views);
  std::vector<ProjectionMatrix> chosen;
  chosen.reserve(views.size());
  for (int v : views) chosen.push_back(views_[static_cast<std::size_t>(v)]);
  return std::make_shared<JosephOperator>(std::move(chosen), layout_, rows_, cols_, options_);
}

void JosephOperator::do_apply(ConstVolumeSpan x, StackSpan y) const { projector_.forward(x, views_, y); }

void JosephOperator::do_apply_adjoint(ConstStackSpan y, VolumeSpan x) const { projector_.back(y, views_, x); }

}  // namespace ctk

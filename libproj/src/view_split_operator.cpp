#include "ctk/proj/view_split_operator.hpp"

#include <stdexcept>

namespace ctk {

ViewSplitOperator::ViewSplitOperator(std::shared_ptr<const ProjectionOperator> local, const Communicator& ranks)
    : local_(std::move(local)), ranks_(ranks) {
  if (!local_) throw std::invalid_argument("ViewSplitOperator: no operator for this rank's views");
}

std::shared_ptr<const ProjectionOperator> ViewSplitOperator::subset(const std::vector<int>& views) const {
  return std::make_shared<ViewSplitOperator>(local_->subset(views), ranks_);
}

void ViewSplitOperator::do_apply(ConstVolumeSpan x, StackSpan y) const { local_->apply(x, y); }

void ViewSplitOperator::do_apply_adjoint(ConstStackSpan y, VolumeSpan x) const {
  local_->apply_adjoint(y, x);
  ranks_.sum(std::span<float>(x.data, x.layout.voxel_count()));
}

std::vector<int> dealt_share(int count, int rank, int ranks) {
  if (ranks < 1 || rank < 0 || rank >= ranks) throw std::invalid_argument("dealt_share: rank outside 0 .. ranks - 1");
  std::vector<int> share;
  for (int i = rank; i < count; i += ranks) share.push_back(i);
  return share;
}

}  // namespace ctk

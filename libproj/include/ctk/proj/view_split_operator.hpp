#pragma once
// A projection operator whose views are spread over the ranks of a run, each holding the whole
// volume: every rank projects its own views, and a back projection is the sum of every rank's
// (one volume summed over the ranks), so the volume stays the same on every rank. The range is
// this rank's views; sums over it are summed over the ranks. A solver on this operator runs as
// on one process: its volume arithmetic is repeated identically on every rank.
#include <memory>
#include <vector>

#include "ctk/core/communicator.hpp"
#include "ctk/proj/projection_operator.hpp"

namespace ctk {

class ViewSplitOperator final : public ProjectionOperator {
 public:
  /// `local`: this rank's views (possibly none). `ranks` must outlive the operator.
  ViewSplitOperator(std::shared_ptr<const ProjectionOperator> local, const Communicator& ranks);

  const VolumeLayout& domain() const override { return local_->domain(); }
  StackShape range() const override { return local_->range(); }
  /// `views` index this rank's views; every rank must ask for its part of the same subset.
  std::shared_ptr<const ProjectionOperator> subset(const std::vector<int>& views) const override;
  double sum_over_range(double part) const override { return ranks_.sum(local_->sum_over_range(part)); }
  const Communicator& ranks() const { return ranks_; }

 private:
  void do_apply(ConstVolumeSpan x, StackSpan y) const override;
  void do_apply_adjoint(ConstStackSpan y, VolumeSpan x) const override;

  std::shared_ptr<const ProjectionOperator> local_;
  const Communicator& ranks_;
};

/// The positions 0 .. count-1 that rank `rank` of `ranks` holds when views are dealt in turn (so
/// every rank's share spans the whole trajectory): rank, rank + ranks, ...
std::vector<int> dealt_share(int count, int rank, int ranks);

}  // namespace ctk

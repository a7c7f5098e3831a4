#pragma once
// A projection operator whose volume is split over the ranks of a run in slabs of z planes, for
// volumes larger than one rank holds. Each rank holds its slab and, of every view, the detector
// rows it owns (each view's rows are split over the ranks, a rank owning rows about where its
// slab projects). Forward, a rank projects its slab onto the rows the slab reaches (its
// footprint) and every row is summed by its owner over the ranks that reach it; for the adjoint,
// each owner hands its rows to the ranks whose footprint holds them, and every rank back projects
// its footprint into its slab. Joseph line integrals add up over slabs exactly (a ray's samples
// interpolate against zero beyond a slab), so the pair equals the whole volume's operator up to
// float rounding. Sums over the range and over the domain are summed over the ranks.
#include <functional>
#include <memory>
#include <vector>

#include "ctk/core/communicator.hpp"
#include "ctk/core/projection_stack.hpp"
#include "ctk/geom/projection_matrix.hpp"
#include "ctk/proj/joseph_projector.hpp"
#include "ctk/proj/projection_operator.hpp"

namespace ctk {

/// Rows [first, first + count) of a view.
struct RowRange {
  int first = 0, count = 0;
  int end() const { return first + count; }
  RowRange intersection(const RowRange& o) const;
};

/// The planes [first, first + count) of the volume's z planes a rank holds: contiguous, dealt as
/// evenly as can be (the first ranks one plane more).
RowRange slab_planes(int planes, int rank, int ranks);

/// The layout of rank `rank`'s slab of `whole`.
VolumeLayout slab_layout(const VolumeLayout& whole, int rank, int ranks);

/// For every view and rank, from the matrices alone (every rank computes the same): the rows the
/// rank's slab projects to (its footprint, with a voxel's margin for the interpolation) and the
/// rows it owns (each view's rows split at the midpoints between the footprints' centres).
class SlabRows {
 public:
  SlabRows(const std::vector<ProjectionMatrix>& views, const VolumeLayout& whole, int detector_rows, int ranks);
  int views() const { return static_cast<int>(footprint_.size()); }
  int ranks() const { return ranks_; }
  const RowRange& footprint(int view, int rank) const;
  const RowRange& owned(int view, int rank) const;
  /// The most rows of any view that `rank` owns, and that its footprint holds.
  int owned_height(int rank) const;
  int footprint_height(int rank) const;
  /// Values `rank` sends per forward and per adjoint projection of all views (rows it computes
  /// that others own, and rows it owns that others' footprints hold), times the detector's columns.
  std::size_t exchanged_rows(int rank) const;

 private:
  int ranks_;
  std::vector<std::vector<RowRange>> footprint_, owned_;  // [view][rank]
};

class SlabSplitOperator final : public ProjectionOperator {
 public:
  /// `views`: every view of the run (each rank the same); `rows` (shared by the ranks' operators)
  /// computed from them; the range is the owned rows of each view, `rows->owned_height(rank)`
  /// high (zeros below a view's own rows). `ranks` must outlive the operator.
  SlabSplitOperator(std::vector<ProjectionMatrix> views, const VolumeLayout& whole, int detector_rows, int detector_cols,
                    std::shared_ptr<const SlabRows> rows, const Communicator& ranks, const ProjectorOptions& options = {});

  const VolumeLayout& domain() const override { return slab_; }
  StackShape range() const override { return {static_cast<int>(view_ids_.size()), height_, cols_}; }
  /// The same split on `views` (indices into this operator's views); the range keeps its height.
  std::shared_ptr<const ProjectionOperator> subset(const std::vector<int>& views) const override;
  double sum_over_range(double part) const override { return ranks_.sum(part); }
  double sum_over_domain(double part) const override { return ranks_.sum(part); }

 private:
  SlabSplitOperator(const SlabSplitOperator& parent, std::vector<int> view_ids);
  void do_apply(ConstVolumeSpan x, StackSpan y) const override;
  void do_apply_adjoint(ConstStackSpan y, VolumeSpan x) const override;
  // The matrices moved so that row 0 of a view's band is the first row of its footprint.
  std::vector<ProjectionMatrix> band_matrices() const;
  // The slab's projection onto the rows it reaches: kept between calls (allocating it for every
  // projection left the heap holding several, measured as peak memory).
  ProjectionStack& band_buffer() const;
  // To each rank q, the rows of every view that `held` gives this rank (view k's rows from
  // view(k), its first row the first held) and `wanted` gives q.
  using RowsOf = const RowRange& (SlabRows::*)(int view, int rank) const;
  std::vector<std::vector<float>> rows_for_each_rank(const std::function<const float*(int)>& view, RowsOf held,
                                                     RowsOf wanted) const;

  std::vector<ProjectionMatrix> all_views_;  // the run's views, as SlabRows indexes them
  std::vector<int> view_ids_;                // this operator's views among them
  VolumeLayout slab_;
  int detector_rows_, cols_, height_, band_height_;
  std::shared_ptr<const SlabRows> rows_;
  const Communicator& ranks_;
  JosephProjector projector_;
  mutable ProjectionStack band_;
};

}  // namespace ctk

#pragma once
// The linear map from a volume to a stack of projections, A, with its exact adjoint A'. Solvers,
// the refinement and the Python binding see only this interface; the Joseph projector on a set of
// views implements it (joseph_operator.hpp), and variants compose with any operator: detector
// binning (binned_projection.hpp), per-pixel weights (weighted_projection.hpp), the mean over an
// arc of sub-views (arc_averaged_projection.hpp). Every operator can restrict itself to a subset
// of its views, which ordered-subset methods and distributed runs need; a range or a domain
// spread over ranks says so through sum_over_range and sum_over_domain.
#include <memory>
#include <vector>

#include "ctk/core/projection_stack.hpp"
#include "ctk/core/volume.hpp"

namespace ctk {

/// The shape of a projection stack.
struct StackShape {
  int views = 0, rows = 0, cols = 0;
  bool operator==(const StackShape&) const = default;
  static StackShape of(const ProjectionStack& y) { return {y.views, y.rows, y.cols}; }
};

class ProjectionOperator {
 public:
  virtual ~ProjectionOperator() = default;

  /// The layout of the volumes A takes.
  virtual const VolumeLayout& domain() const = 0;
  /// The shape of the stacks A gives.
  virtual StackShape range() const = 0;

  /// y = A x. x must have the domain's layout (std::invalid_argument otherwise); y is reshaped to
  /// the range if it differs, and overwritten.
  void apply(ConstVolumeSpan x, ProjectionStack& y) const;
  /// x = A' y. y must have the range's shape; x takes the domain's layout and is overwritten.
  void apply_adjoint(ConstStackSpan y, Volume& x) const;
  /// The same into memory held elsewhere (a numpy array): y must have the range's shape, x the
  /// domain's layout.
  void apply(ConstVolumeSpan x, StackSpan y) const;
  void apply_adjoint(ConstStackSpan y, VolumeSpan x) const;

  /// The operator on `views` only (indices into this operator's views, in the order given), so
  /// that its range has views.size() views. Throws std::out_of_range for an index out of range.
  virtual std::shared_ptr<const ProjectionOperator> subset(const std::vector<int>& views) const = 0;

  /// A sum over the range from this process's part of it: the part itself, unless the range is
  /// spread over ranks (view_split_operator.hpp), when it is every rank's part summed. Solvers
  /// pass every reduction over projections (a residual's norm, a curvature) through it.
  virtual double sum_over_range(double part) const { return part; }
  /// The same over the domain: the part itself, unless the volume is split into slabs over ranks
  /// (slab_split_operator.hpp). Solvers pass every sum over voxels (a gradient's norm, a
  /// penalty) through it.
  virtual double sum_over_domain(double part) const { return part; }

  /// A zero stack of the range's shape, a zero volume of the domain's layout.
  ProjectionStack range_zeros() const;
  Volume domain_zeros() const;

 protected:
  // Called with shapes checked: x has the domain's layout, y the range's shape.
  virtual void do_apply(ConstVolumeSpan x, StackSpan y) const = 0;
  virtual void do_apply_adjoint(ConstStackSpan y, VolumeSpan x) const = 0;
  // Throws std::out_of_range naming the first index of `views` outside [0, range().views).
  void check_subset(const std::vector<int>& views) const;
};

}  // namespace ctk

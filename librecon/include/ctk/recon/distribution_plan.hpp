#pragma once
// How a reconstruction spreads over the ranks of an MPI run, decided from the matrices before
// any image is read: views split (each rank its share of the views and the whole volume; the back
// projection summed over the ranks) or slabs (each rank a slab of z planes and the detector rows
// it owns; rows a slab reaches but another rank owns exchanged, view_split_operator.hpp and
// slab_split_operator.hpp). Both are planned, the largest rank's memory and the bytes a rank
// hands to the others per iteration; views split is picked while it fits, slabs when it does not.
#include <cstddef>
#include <memory>
#include <string>
#include <vector>

#include "ctk/geom/projection_matrix.hpp"
#include "ctk/proj/slab_split_operator.hpp"
#include "ctk/recon/memory_plan.hpp"
#include "ctk/recon/regulariser.hpp"

namespace ctk {

enum class Decomposition { automatic, views, slabs };
const char* to_string(Decomposition d);
/// "auto", "views", "slabs"; std::invalid_argument naming the others.
Decomposition decomposition_from_string(const std::string& name);

struct DistributionPlan {
  int ranks = 1;
  Decomposition decomposition = Decomposition::views;  // the one picked
  int views_per_rank = 0;                              // views split: the largest share
  int planes_per_rank = 0;                             // slabs: the thickest slab
  MemoryPlan views_memory, slabs_memory;               // the largest rank's
  /// Bytes rank `rank` hands to the others per iteration (per epoch for OS-SQS): the summed
  /// volume and the step's scalars (views split); the rows exchanged and the scalars (slabs).
  std::size_t views_bytes_per_iteration = 0, slabs_bytes_per_iteration = 0;
  std::string slabs_refused;             // why slabs cannot run this solver (empty: they can)
  std::shared_ptr<const SlabRows> rows;  // the slabs' rows, when slabs can run

  const MemoryPlan& memory() const { return decomposition == Decomposition::slabs ? slabs_memory : views_memory; }
  std::size_t bytes_per_iteration() const {
    return decomposition == Decomposition::slabs ? slabs_bytes_per_iteration : views_bytes_per_iteration;
  }
  /// Both plans on a line each, and which is picked.
  std::string describe() const;
};

/// `views`: the run's ok matrices; `asked`: automatic picks views split while its memory fits
/// `available_bytes`, else slabs. Throws std::invalid_argument when the decomposition asked for
/// (or the only one that fits) cannot run the solver, or with more ranks than planes for slabs.
/// On one rank: views split, nothing exchanged.
DistributionPlan plan_distribution(const SolverShape& solver, const VolumeLayout& layout,
                                   const std::vector<ProjectionMatrix>& views, int rows, int cols, int subsets, int ranks,
                                   int rank, std::size_t available_bytes, Decomposition asked);

}  // namespace ctk

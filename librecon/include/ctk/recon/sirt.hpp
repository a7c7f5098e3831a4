#pragma once
// SIRT, the robust baseline: x <- x + C A' R (b - A x), with R and C the inverse row and column
// sums of A (rays and voxels no view sees are left alone); optionally kept non-negative.
#include <vector>

#include "ctk/proj/projection_operator.hpp"
#include "ctk/recon/iteration_log.hpp"
#include "ctk/recon/solver_state.hpp"

namespace ctk {

struct SirtOptions {
  int iterations = 100;
  double relaxation = 1.0;  // in (0, 2)
  bool non_negative = true;
  void validate() const;  // std::invalid_argument naming the field
};

/// `b` has A's range shape, `x` (the start, and the result) A's domain layout.
SolverReport solve_sirt(const ProjectionOperator& A, const ProjectionStack& b, Volume& x, const SirtOptions& options,
                        const IterationCallback& on_iteration = {}, const Checkpointing* checkpointing = nullptr,
                        const StoppingRule& stopping = {});

}  // namespace ctk

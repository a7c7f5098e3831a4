#pragma once
// Weighted least squares with a quadratic penalty,
//   minimise 1/2 ||W^(1/2) (A x - b)||^2 + 1/2 lambda ||G x||^2,
// by conjugate gradients on the normal equations (A'WA + lambda G'G) x = A'W b: one forward and
// one back projection per iteration. The objective falls at every iteration (CG minimises it over
// a growing Krylov space); the run stops after `iterations` or when the gradient has fallen by
// `tolerance` relative to the start.
#include <vector>

#include "ctk/proj/joseph_projector.hpp"
#include "ctk/recon/iteration_log.hpp"
#include "ctk/recon/regulariser.hpp"

namespace ctk {

struct WlsOptions {
  int iterations = 30;
  double tolerance = 1e-4;
  double lambda = 0;
  Regulariser regulariser = Regulariser::identity;
};

/// `x` is the starting point (zeros for a cold start) and receives the result. `weights` may be
/// null (unit weights); otherwise the same shape as `b`.
SolverReport solve_wls_cg(const JosephProjector& A, const std::vector<ProjectionMatrix>& views,
                          const ProjectionStack& b, const ProjectionStack* weights, Volume& x,
                          const WlsOptions& options, const IterationCallback& on_iteration = {});

}  // namespace ctk

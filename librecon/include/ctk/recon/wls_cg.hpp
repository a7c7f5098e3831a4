#pragma once
// Weighted least squares with a quadratic penalty,
//   minimise 1/2 ||W^(1/2) (A x - b)||^2 + 1/2 lambda ||G x||^2,
// by conjugate gradients on the normal equations (A'WA + lambda G'G) x = A'W b: one forward and
// one back projection per iteration. The objective falls at every iteration (CG minimises it over
// a growing Krylov space); the run stops after `iterations` or when the gradient has fallen by
// `tolerance` relative to the start. With `checkpointing` it saves its state (iterate, residual,
// gradient, direction) as asked and continues a saved one exactly.
// Preconditioned by the diagonal D = A'WA1 + lambda c (separable_curvature.hpp), CG runs on
// D^(-1/2) H D^(-1/2) instead: the same minimiser, with the scale differences between voxels
// (the weights, the edges of the field of view, voxels seen by few views) taken out, for one more
// projection pair at the start and one more volume.
#include <string>
#include <vector>

#include "ctk/proj/projection_operator.hpp"
#include "ctk/recon/iteration_log.hpp"
#include "ctk/recon/regulariser.hpp"
#include "ctk/recon/solver_state.hpp"

namespace ctk {

enum class CgPreconditioner { none, diagonal };
const char* to_string(CgPreconditioner p);
/// "none" or "diagonal"; std::invalid_argument naming them.
CgPreconditioner cg_preconditioner_from_string(const std::string& name);

struct WlsOptions {
  int iterations = 30;
  double tolerance = 1e-4;
  double lambda = 0;
  Regulariser regulariser = Regulariser::identity;
  CgPreconditioner preconditioner = CgPreconditioner::none;
  /// false: the gradient after the last iteration is not computed (one back projection less; the
  /// last log entry then repeats the previous relative gradient). For callers that only want x.
  bool gradient_after_last = true;
  void validate() const;  // std::invalid_argument naming the field
};

/// `x` is the starting point (zeros for a cold start, A's domain layout) and receives the result.
/// `b` has A's range shape; `weights` may be null (unit weights), otherwise the same shape as `b`.
/// `stopping` may end the run before `iterations` (its reason becomes the stop reason).
SolverReport solve_wls_cg(const ProjectionOperator& A, const ProjectionStack& b, const ProjectionStack* weights, Volume& x,
                          const WlsOptions& options, const IterationCallback& on_iteration = {},
                          const Checkpointing* checkpointing = nullptr, const StoppingRule& stopping = {});

/// The same for a caller that keeps the residual A x - b between calls (an incremental
/// reconstruction that adds views): `residual` holds it on entry and on return, so the start
/// costs no forward projection.
SolverReport solve_wls_cg(const ProjectionOperator& A, const ProjectionStack& b, const ProjectionStack* weights, Volume& x,
                          ProjectionStack& residual, const WlsOptions& options, const IterationCallback& on_iteration = {},
                          const Checkpointing* checkpointing = nullptr, const StoppingRule& stopping = {});

}  // namespace ctk

#pragma once
// Ordered-subsets separable quadratic surrogates (OS-SQS) with Nesterov momentum, for the same
// weighted objective as WLS-CG,
//   minimise 1/2 ||W^(1/2) (A x - b)||^2 + 1/2 lambda ||G x||^2   (x >= 0 if asked),
// or with the edge-preserving Huber penalty in place of the quadratic one (its curvature then
// follows the volume: huber_penalty.hpp).
// SQS majorises the objective by a separable quadratic with curvature D = A'W A 1 + lambda c
// (c: 1 for the identity penalty, 12 for the gradient penalty, the bound of G'G's row sums), so
// a step x - grad / D never raises the cost, and non-negativity is a clip. Ordered subsets take
// that step once per subset, with the subset's gradient scaled by the subset count: an epoch
// (every view once) then moves as far as many full steps for the price of one forward and one
// back projection. Momentum (Nesterov's, as Kim, Ramani and Fessler combined it with ordered
// subsets, IEEE TMI 2015) accelerates further. With one subset and no momentum this is plain SQS,
// whose cost falls at every epoch; with many subsets it approaches the solution fast and then
// hovers near it (a limit cycle whose size grows with the subset count): where a converged
// solution is wanted, continue with fewer subsets.
#include <functional>
#include <vector>

#include "ctk/proj/projection_operator.hpp"
#include "ctk/recon/iteration_log.hpp"
#include "ctk/recon/regulariser.hpp"

namespace ctk {

struct OsSqsOptions {
  int epochs = 6;  // passes over every view
  bool momentum = true;
  bool non_negative = true;
  double lambda = 0;
  Regulariser regulariser = Regulariser::identity;
  /// > 0: lambda weighs the edge-preserving Huber penalty of neighbour differences with this
  /// delta (huber_penalty.hpp) instead of the quadratic `regulariser`.
  double huber_delta = 0;
  /// true: the full cost is computed after every epoch (one more forward projection each). false:
  /// the log's data term is the sum of the subsets' data terms at the iterates they saw.
  bool exact_cost = false;
  void validate() const;  // std::invalid_argument naming the field
};

/// The stop reason of a run stopped on request between epochs (there is no state to continue:
/// momentum restarts, so a new run from the volume reached is a different run).
inline constexpr const char* kStoppedWithoutState = "stopped on request after an epoch";

/// `subsets` partition A's views (every view in exactly one; std::invalid_argument otherwise).
/// `x` is the start (A's domain layout; zeros for a cold start) and receives the result. `b` has
/// A's range shape; `weights` may be null (unit weights). The log has one entry per epoch.
/// `stopping` may end the run before `epochs` (its reason becomes the stop reason).
SolverReport solve_os_sqs(const ProjectionOperator& A, const ProjectionStack& b, const ProjectionStack* weights, Volume& x,
                          const std::vector<std::vector<int>>& subsets, const OsSqsOptions& options,
                          const IterationCallback& on_iteration = {}, const std::function<bool()>& stop_requested = {},
                          const StoppingRule& stopping = {});

}  // namespace ctk

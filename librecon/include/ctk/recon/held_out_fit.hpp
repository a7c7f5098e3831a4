#pragma once
// When to stop an iterative reconstruction that nothing else stops. Unregularised, its error
// against the truth falls to a minimum and rises again as the solver starts fitting the noise
// (bench_stopping_rule: on the standard problem at 10^4 counts OS-SQS is best after 2 epochs and
// 52 % worse after 8; WLS-CG best after 12 iterations and 39 % worse after 24). The truth is
// unknown, but views the solver never saw judge an iterate fairly: their weighted misfit falls
// while the solver learns what every view shares. Once it learns what only the noise of its own
// views holds, the held-out misfit rises, or keeps falling by amounts the held-out data's own
// noise could produce: the image has stopped improving where the data can tell. So a small share
// of the views, spread over the scan's directions, is held out of the solve; after every
// iteration their misfit is measured, and the run ends at the first iteration whose improvement is
// not significant (kHeldOutSignificance), with the last iterate that improved as its result.
// For OS-SQS that last improving epoch is often one past the best: the held-out views judge what
// projections see, and the noise the solver starts to fit lies in the finest detail, which shows
// in them later than in the image. So reconstruction_run returns the improving epoch before it
// (HeldOutResult::one_before), when that one is past the first. On the eight standard cases of
// bench_stopping_rule (scale 2) that is the run's best epoch in all eight (the last improving
// one: up to 4.1 % above it; the mean of the two, returned before: 0.982 to 1.011 of it), and at
// the thesis' size (thesis_pipeline.py) the best epoch again (the mean: 1.037). Where the rule
// stops early (walnut, spherical, 10^3 counts, 120 views) it is further off: 1.18 times the best,
// the mean 1.14, the last improving epoch 1.11. WLS-CG keeps its last improving iterate: CG's
// early iterates differ most, and on the unit test's noisy scan the one before the last improving
// was 1.11 times the best, which the last improving one was.
#include <Eigen/Core>
#include <cstddef>
#include <memory>
#include <nlohmann/json.hpp>
#include <vector>

#include "ctk/core/projection_stack.hpp"
#include "ctk/core/volume.hpp"
#include "ctk/geom/projection_matrix.hpp"
#include "ctk/proj/projection_operator.hpp"
#include "ctk/recon/iteration_log.hpp"
#include "ctk/recon/memory_plan.hpp"

namespace ctk {

/// The positions (ascending) of the views to hold out: one of `every` ordered subsets of the views
/// (ordered_subsets.hpp: spread over their source directions seen from `centre_mm`), so about one
/// view in `every`. Empty when there are fewer than `every` views (or `every` is 0).
std::vector<int> held_out_positions(const std::vector<ProjectionMatrix>& views, int every,
                                    const Eigen::Vector3d& centre_mm = Eigen::Vector3d::Zero());

/// How many standard errors of the held-out noise an improvement of the misfit must exceed to
/// count: a one-sided test at 2.3 %.
inline constexpr double kHeldOutSignificance = 2.0;

/// The iterate a run stopped by the rule returns.
enum class HeldOutResult {
  last_improving,    // the last iterate whose held-out fit improved
  one_before,        // the improving iterate before that one, when it is past the first iteration
  mean_of_last_two,  // the mean of those two, when both are past the first iteration
};

/// What a default run of `method` returns (above): OS-SQS the improving epoch before the last, the
/// others their last improving iterate.
HeldOutResult held_out_result(ReconstructionMethod method);
/// The volumes a HeldOutFit returning `which` keeps beside the solver's own.
int held_out_volumes(HeldOutResult which);

class HeldOutFit {
 public:
  /// `A` projects onto the held-out views, whose line integrals are `b` and weights `w` (no views:
  /// unit weights). An operator spread over ranks sums the misfit over them, so every rank
  /// decides alike; `view_indices` are then every rank's held-out views (their scan indices, for
  /// the report; empty: `b`'s views), of `pixels_per_view` each (0: `b`'s).
  HeldOutFit(std::shared_ptr<const ProjectionOperator> A, ProjectionStack b, ProjectionStack w,
             std::vector<int> view_indices = {}, std::size_t pixels_per_view = 0);

  /// After iteration `iteration` (0: the start): the misfit of `x`; `x` is kept as the result when
  /// it improved on the one before by more than the held-out data's noise can explain.
  void observe(int iteration, const Volume& x);
  /// Ends the run once the last observed iteration brought no such improvement.
  StoppingRule rule() const;
  /// Which iterate the result is (HeldOutResult::last_improving unless asked; the others keep
  /// one volume more). Call before the first observe.
  void return_result(HeldOutResult which);
  /// `x` becomes the result return_result chose (unchanged if it is the last iterate); returns the
  /// last improving iteration.
  int restore_best(Volume& x);
  /// {"views": the held-out view count, "view_indices" (when given), "iterations", "fit":
  /// 1/2 ||W^(1/2) (A x - b)||^2 at each, "best_iteration", "result_iterations": the iterates the
  /// result is (the mean of)}.
  nlohmann::json report() const;

 private:
  std::shared_ptr<const ProjectionOperator> A_;
  ProjectionStack b_, w_, projected_, previous_;
  std::vector<int> view_indices_;
  int views_ = 0;
  double rays_ = 0;  // data, weights, A x now and at the iterate before
  std::vector<int> iterations_;
  std::vector<double> fits_;
  int best_iteration_ = -1;
  double best_fit_ = 0;
  bool significant_ = true;  // the last iteration improved the fit beyond the held-out data's noise
  Volume best_;
  HeldOutResult result_ = HeldOutResult::last_improving;
  int before_best_iteration_ = -1;
  Volume before_best_;  // unless last_improving: the improving iterate before best_
  // The iterations the result is made of.
  std::vector<int> result_iterations() const;
};

}  // namespace ctk

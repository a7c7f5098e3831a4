#pragma once
// The covariance of a least-squares problem's global parameters with its per-view parameters
// marginalised, by the Schur complement of the per-view blocks in J'J: each view's block is
// eliminated on its own, so the cost grows with the views, not with their cube. On a scan of 897
// views (5,400 pose parameters) Ceres' dense SVD of the whole Jacobian had held one core for 7
// minutes and 11.6 GB inside one diagnosis step when it was stopped; with this the whole
// diagnosis took 33 s (benchmarks/thesis_pipeline.py, docs/reconstruction-quality.md).
#include <ceres/problem.h>

#include <Eigen/Core>
#include <vector>

namespace ctk {

/// (J'J)^+ restricted to `globals`, in their order and tangent spaces, with every block of
/// `per_view` free and marginalised; eigenvalues below 1e-14 of the largest count as zero (a gauge
/// or confounded effects leave directions unfixed), as Ceres' dense SVD covariance drops them.
/// False when a residual block touches two `per_view` blocks (then the elimination is not
/// block by block) or the evaluation fails.
bool marginal_covariance(ceres::Problem& problem, const std::vector<double*>& per_view, const std::vector<const double*>& globals,
                         Eigen::MatrixXd& covariance);

}  // namespace ctk

#pragma once
// The curvature of the separable quadratic that majorises weighted least squares (De Pierro's
// convexity argument, Erdogan and Fessler 1999): per voxel D_j = sum_i a_ij w_i sum_k a_ik, that
// is D = A'W A 1, plus the quadratic penalty's bound lambda c (c = 1 for the identity, 12 for the
// gradient: the largest row sum of |G'G|). OS-SQS steps by 1 / D; WLS-CG preconditions by it.
#include <vector>

#include "ctk/proj/projection_operator.hpp"
#include "ctk/recon/regulariser.hpp"

namespace ctk {

/// D = A'W A 1 (`weights` null: unit weights). With `subsets` (a partition of A's views) it is
/// summed subset by subset, so no stack larger than one subset's is held; otherwise one stack of
/// A's range is held while it runs. One forward and one back projection of every view.
Volume separable_data_curvature(const ProjectionOperator& A, const ProjectionStack* weights,
                                const std::vector<std::vector<int>>& subsets = {});

/// lambda c: the bound on the quadratic penalty's curvature that keeps the surrogate above it.
double separable_penalty_curvature(Regulariser regulariser, double lambda);

}  // namespace ctk

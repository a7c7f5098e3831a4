#pragma once
// Views grouped into ordered subsets for methods that update the volume once per subset
// (os_sqs.hpp). A subset stands in for the whole scan, scaled by the subset count, so each must
// see the object from directions spread over everything the scan covers: a subset of
// neighbouring views (an arc, one patch of a sphere) makes its update a poor substitute for the
// full gradient, and the method wanders. Each subset starts from one of the scan's most
// separated source directions (farthest-point order; a line and its opposite count as the same
// direction), and then the subsets take turns, each taking the view left that is farthest from
// its own members. This holds whatever the trajectory: views evenly spaced on a circle come out
// as the usual interleaved subsets, and views bunched in one part of a sphere are spread over all.
#include <Eigen/Core>
#include <vector>

#include "ctk/geom/projection_matrix.hpp"

namespace ctk {

/// `count` subsets (at most one per view) of the views whose source directions from the volume's
/// centre are `directions` (any length; zero vectors are refused with std::invalid_argument).
/// The subsets differ in size by at most one view.
std::vector<std::vector<int>> ordered_subsets(const std::vector<Eigen::Vector3d>& directions, int count);

/// The same from the views' matrices: each source's direction from `centre_mm`.
std::vector<std::vector<int>> ordered_subsets(const std::vector<ProjectionMatrix>& views, int count,
                                              const Eigen::Vector3d& centre_mm = Eigen::Vector3d::Zero());

/// The largest angle (degrees, lines: at most 90) between any view's direction and the nearest
/// direction of `subset`: how well one subset stands for the whole scan.
double subset_coverage_gap_deg(const std::vector<Eigen::Vector3d>& directions, const std::vector<int>& subset);

}  // namespace ctk

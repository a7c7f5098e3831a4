#pragma once
// Which detection is which sphere. The first-guess pose may be off by millimetres, so the
// predicted pattern is shifted onto the detections, then detections and spheres are paired by an
// optimal (minimum total distance) assignment, gated. A helix is self-similar under some shifts,
// so the voting proposes several shifts and the caller keeps the one a pose fit confirms.
#include <Eigen/Core>
#include <vector>

#include "ctk/calib/sphere_detection.hpp"

namespace ctk {

/// Minimum-cost assignment (Hungarian method with potentials, O(n^2 m)): result[row] is the
/// column given to that row, -1 when there are more rows than columns and the row got none.
std::vector<int> assign_min_cost(const Eigen::MatrixXd& cost);

struct SphereMatch {
  int sphere = -1;
  int detection = -1;
  double distance_px = 0;  // after the common shift
};

/// Shifts of the whole predicted pattern (at most `search_px` long) that many sphere-detection
/// pairs agree on, most votes first (2 px bins), at most `count`, zero always included.
std::vector<Eigen::Vector2d> candidate_shifts(const std::vector<Eigen::Vector2d>& predicted, const std::vector<bool>& usable,
                                              const std::vector<SphereDetection>& detections, double search_px, int count);

/// `predicted[k]` is sphere k's predicted position; spheres with `usable[k]` false (off the
/// detector, overlapping another) take no part. Pairs farther than `gate_px` after `shift` are dropped.
std::vector<SphereMatch> match_spheres(const std::vector<Eigen::Vector2d>& predicted, const std::vector<bool>& usable,
                                       const std::vector<SphereDetection>& detections, const Eigen::Vector2d& shift,
                                       double gate_px);

}  // namespace ctk

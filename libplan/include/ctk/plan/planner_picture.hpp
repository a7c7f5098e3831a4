#pragma once
// What the planner reads off its picture of the sample before each draw: the absorbers, each
// candidate direction's damage (longest path through them) and the edges' demand. The picture is
// the coarse reconstruction of the views so far (plan_trajectory.hpp), or the truth when the rule
// itself is checked apart from how well the scout shows the sample (plan_on_picture).
#include <Eigen/Core>
#include <vector>

#include "ctk/core/volume.hpp"
#include "ctk/plan/absorber_segmentation.hpp"
#include "ctk/plan/direction_damage.hpp"
#include "ctk/plan/edge_tangency.hpp"
#include "ctk/plan/view_planner.hpp"

namespace ctk {

// How a picture is read.
struct PictureReading {
  SegmentationOptions segmentation;  // its region is also where edges are looked for
  EdgeTangencyOptions edge_tangency;
  bool edge_demand = true;  // an edge share b of 0 never uses it, and it is the costlier half
  bool median = true;       // through a 3^3 median first (picture_median.hpp)
};

struct PlannerPicture {
  AbsorberSegmentation segmentation;
  std::vector<double> damage_mm;    // per candidate (all zero when nothing was segmented)
  std::vector<double> edge_demand;  // per candidate, relative to its mean; empty when not wanted
  /// The damage (none when nothing was segmented) and the demand, handed to the planner.
  void give_to(ViewPlanner& planner) const;
};

/// Reads `picture` for `candidates` as `reading` says.
PlannerPicture read_planner_picture(const Volume& picture, const std::vector<Eigen::Vector3d>& candidates,
                                    const PictureReading& reading, const DamageGeometry& geometry);

}  // namespace ctk

#pragma once
// The planner's pictures: the candidate directions on two equal-area maps, coloured by the damage
// the last picture of the sample predicts for them and by the view density its edges want, with
// the scout, the planned and the refused directions marked; and the comparison of trajectories:
// a slice of each reconstruction beside the truth's, and line profiles against the truth's.
#include <filesystem>
#include <string>
#include <vector>

#include "ctk/plan/plan_trajectory.hpp"
#include "ctk/plan/trajectory_quality.hpp"

namespace ctk {

void write_plan_map_png(const PlanningResult& result, const std::filesystem::path& png);

struct ComparedTrajectory {
  std::string name;
  const Volume* reconstruction = nullptr;
  TrajectoryQuality quality;
};

/// Slices across z through the profiles' voxel, then each trajectory's x profile against the truth.
void write_trajectory_comparison_png(const std::vector<ComparedTrajectory>& trajectories, const Volume& truth,
                                     const std::filesystem::path& png);

}  // namespace ctk

#pragma once
// Joint logs for simulated robot scans: a circular scan spins joint 7 (holder axis on the flange
// axis); a spherical scan looks along given holder-frame directions, the numerical IK placing the
// holder centre at the isocentre with the wanted orientation. Directions the arm cannot reach
// within its joint limits are kept, without joints, with the reason.
#include <optional>
#include <string>
#include <vector>

#include "ctk/geom/panda_setup.hpp"

namespace ctk {

struct PlannedView {
  Eigen::Vector3d direction{0, 0, 1};   // beam direction seen in the holder frame
  std::optional<panda::Joints> joints;  // absent: unreachable
  std::string note;                     // why unreachable
};

std::vector<PlannedView> circular_robot_trajectory(const PandaSetup& setup, int count);

/// For each direction, the first of several rolls about the beam (0, 90, 180, 270, then the
/// diagonals, degrees) that the IK reaches, from the previous view's joints or the ready pose.
std::vector<PlannedView> spherical_robot_trajectory(const PandaSetup& setup, const std::vector<Eigen::Vector3d>& directions);

}  // namespace ctk

#pragma once
// Numerical inverse kinematics of the Panda, used only to make joint logs for simulated scans
// (the toolkit otherwise treats the robot as an opaque pose source). Ceres minimises the pose
// error of the forward kinematics with the joints bounded inside their limits.
#include <string>

#include "ctk/geom/panda.hpp"

namespace ctk {

struct IkSolution {
  bool reached = false;
  panda::Joints q{};
  double position_error_mm = 0;
  double rotation_error_deg = 0;
};

/// Joints whose flange pose is `T_base_flange`, starting from `start`, each joint kept at least
/// `margin_rad` inside its limits. `reached` when the pose is met to 1e-4 mm and 1e-5 deg.
IkSolution solve_panda_ik(const Rigid& T_base_flange, const panda::Joints& start, double margin_rad = 0.02);

}  // namespace ctk

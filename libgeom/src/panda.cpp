#include "ctk/geom/panda.hpp"

#include <cstdio>

namespace ctk::panda {

const std::array<DhRow, kJointCount + 1>& dh_table() {
  // Franka Emika documentation, "Denavit-Hartenberg parameters" (modified/Craig convention), in mm.
  static const std::array<DhRow, kJointCount + 1> table{{
      {0.0, 333.0, 0.0},
      {0.0, 0.0, -M_PI / 2},
      {0.0, 316.0, M_PI / 2},
      {82.5, 0.0, M_PI / 2},
      {-82.5, 384.0, -M_PI / 2},
      {0.0, 0.0, M_PI / 2},
      {88.0, 0.0, M_PI / 2},
      {0.0, 107.0, 0.0},  // flange
  }};
  return table;
}

const std::array<JointLimit, kJointCount>& joint_limits() {
  // Franka Emika datasheet, joint space limits (rad).
  static const std::array<JointLimit, kJointCount> limits{{
      {-2.8973, 2.8973},
      {-1.7628, 1.7628},
      {-2.8973, 2.8973},
      {-3.0718, -0.0698},
      {-2.8973, 2.8973},
      {-0.0175, 3.7525},
      {-2.8973, 2.8973},
  }};
  return limits;
}

std::vector<int> joints_out_of_limits(const Joints& q) {
  std::vector<int> out;
  for (int i = 0; i < kJointCount; ++i) {
    const auto& l = joint_limits()[static_cast<std::size_t>(i)];
    if (!(q[static_cast<std::size_t>(i)] >= l.lower_rad && q[static_cast<std::size_t>(i)] <= l.upper_rad)) out.push_back(i);
  }
  return out;
}

std::string describe_limit_violations(const Joints& q) {
  std::string text;
  for (int i : joints_out_of_limits(q)) {
    const auto& l = joint_limits()[static_cast<std::size_t>(i)];
    char buffer[128];
    std::snprintf(buffer, sizeof buffer, "%sq%d = %.4f rad outside [%.4f, %.4f]", text.empty() ? "" : "; ", i + 1,
                  q[static_cast<std::size_t>(i)], l.lower_rad, l.upper_rad);
    text += buffer;
  }
  return text;
}

Rigid forward_kinematics(const Joints& q) {
  Rigid T;
  T.matrix() = forward_kinematics_matrix<double>(q.data());
  return T;
}

}  // namespace ctk::panda

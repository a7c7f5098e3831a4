#pragma once
// Franka Emika Panda forward kinematics, from the manufacturer's modified (Craig) DH table with
// the flange (d = 107 mm) included; millimetres. No KDL, no ROS: the robot is a pose source.
#include <Eigen/Geometry>
#include <array>
#include <string>
#include <vector>

#include "ctk/geom/rigid.hpp"

namespace ctk::panda {

inline constexpr int kJointCount = 7;
using Joints = std::array<double, kJointCount>;

struct DhRow {
  double a_mm, d_mm, alpha_rad;  // Craig: T = RotX(alpha) TransX(a) RotZ(theta) TransZ(d)
};
/// Rows for joints 1..7 then the flange (theta fixed at 0).
const std::array<DhRow, kJointCount + 1>& dh_table();

struct JointLimit {
  double lower_rad, upper_rad;
};
const std::array<JointLimit, kJointCount>& joint_limits();

/// 0-based indices of joints outside their limits (empty when all are within).
std::vector<int> joints_out_of_limits(const Joints& q);
/// "q4 = -0.01 rad outside [-3.0718, -0.0698]; ..." or "" when within limits.
std::string describe_limit_violations(const Joints& q);

/// T_base_flange as a 4x4 homogeneous matrix; templated so solvers can differentiate through it
/// (joint offsets). `q` points to 7 joint angles in radians.
template <typename T>
Eigen::Matrix<T, 4, 4> forward_kinematics_matrix(const T* q) {
  Eigen::Matrix<T, 4, 4> M = Eigen::Matrix<T, 4, 4>::Identity();
  const auto& table = dh_table();
  for (int i = 0; i <= kJointCount; ++i) {
    const T theta = i < kJointCount ? q[i] : T(0);
    using std::cos;
    using std::sin;
    const double ca = std::cos(table[i].alpha_rad), sa = std::sin(table[i].alpha_rad);
    const T ct = cos(theta), st = sin(theta);
    Eigen::Matrix<T, 4, 4> A;
    A << ct, -st, T(0), T(table[i].a_mm), st * ca, ct * ca, T(-sa), T(-sa * table[i].d_mm), st * sa, ct * sa, T(ca),
        T(ca * table[i].d_mm), T(0), T(0), T(0), T(1);
    M = M * A;
  }
  return M;
}

/// T_base_flange (mm). Does not check limits: callers that take joints from a log check them.
Rigid forward_kinematics(const Joints& q);

}  // namespace ctk::panda

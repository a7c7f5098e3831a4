#pragma once
// Rigid transforms. T_A_B maps coordinates in frame B to frame A: x_A = T_A_B * x_B.
#include <Eigen/Geometry>

#include "ctk/core/json_access.hpp"

namespace ctk {

using Rigid = Eigen::Isometry3d;

Rigid make_rigid(const Eigen::Matrix3d& R, const Eigen::Vector3d& t);

/// Rotation about a unit axis (right hand), radians.
Eigen::Matrix3d rotation_about(const Eigen::Vector3d& axis, double angle_rad);

/// Rotation from a rotation vector (axis * angle, radians) — the parametrisation the solvers use.
Eigen::Matrix3d rotation_from_vector(const Eigen::Vector3d& rotation_vector);
Eigen::Vector3d rotation_vector(const Eigen::Matrix3d& R);

/// Angle of the rotation R, degrees (0 .. 180).
double rotation_angle_deg(const Eigen::Matrix3d& R);

/// True when R is orthonormal with det +1 to `tolerance`.
bool is_rotation(const Eigen::Matrix3d& R, double tolerance = 1e-6);

/// Reads { "R": 3x3, "t_mm": [x, y, z] }; R must be a proper rotation.
Rigid rigid_from_json(const JsonNode& node);
nlohmann::json rigid_to_json(const Rigid& T);

}  // namespace ctk

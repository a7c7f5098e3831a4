#include "ctk/geom/rigid.hpp"

#include <cmath>

namespace ctk {

Rigid make_rigid(const Eigen::Matrix3d& R, const Eigen::Vector3d& t) {
  Rigid T = Rigid::Identity();
  T.linear() = R;
  T.translation() = t;
  return T;
}

Eigen::Matrix3d rotation_about(const Eigen::Vector3d& axis, double angle_rad) {
  return Eigen::AngleAxisd(angle_rad, axis.normalized()).toRotationMatrix();
}

Eigen::Matrix3d rotation_from_vector(const Eigen::Vector3d& rotation_vector) {
  const double angle = rotation_vector.norm();
  if (angle < 1e-300) return Eigen::Matrix3d::Identity();
  return Eigen::AngleAxisd(angle, rotation_vector / angle).toRotationMatrix();
}

Eigen::Vector3d rotation_vector(const Eigen::Matrix3d& R) {
  const Eigen::AngleAxisd aa(R);
  return aa.axis() * aa.angle();
}

double rotation_angle_deg(const Eigen::Matrix3d& R) { return Eigen::AngleAxisd(R).angle() * 180.0 / M_PI; }

bool is_rotation(const Eigen::Matrix3d& R, double tolerance) {
  return (R * R.transpose() - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff() <= tolerance &&
         std::abs(R.determinant() - 1.0) <= tolerance;
}

Rigid rigid_from_json(const JsonNode& node) {
  node.warn_unknown_keys({"R", "t_mm"});
  const Eigen::Matrix3d R = node.at("R").matrix3();
  if (!is_rotation(R, 1e-6)) node.at("R").fail("not a rotation matrix (must be orthonormal with determinant +1 to 1e-6)");
  return make_rigid(R, node.at("t_mm").position_mm());
}

nlohmann::json rigid_to_json(const Rigid& T) {
  nlohmann::json R = nlohmann::json::array();
  for (int r = 0; r < 3; ++r) R.push_back({T.linear()(r, 0), T.linear()(r, 1), T.linear()(r, 2)});
  return {{"R", R}, {"t_mm", {T.translation().x(), T.translation().y(), T.translation().z()}}};
}

}  // namespace ctk

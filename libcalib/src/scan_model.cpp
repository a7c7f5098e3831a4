#include "ctk/calib/scan_model.hpp"

namespace ctk {

const char* effect_name(Effect e) {
  switch (e) {
    case Effect::robot_base_frame: return "robot_base_frame";
    case Effect::holder_mount: return "holder_mount";
    case Effect::joint_offsets: return "joint_offsets";
    case Effect::source_drift: return "source_drift";
    case Effect::sphere_positions: return "sphere_positions";
    case Effect::detector_distortion: return "detector_distortion";
    case Effect::detector_intrinsics: return "detector_intrinsics";
  }
  return "?";
}

bool needs_robot(Effect e) {
  return e == Effect::robot_base_frame || e == Effect::holder_mount || e == Effect::joint_offsets;
}

namespace {
Rigid offset_rigid(const double* p) {
  return make_rigid(rotation_from_vector(Eigen::Vector3d(p[0], p[1], p[2])), Eigen::Vector3d(p[3], p[4], p[5]));
}
}  // namespace

Rigid robot_predicted_pose(const DeclaredSetup& s, const EffectParameters& p, const panda::Joints& q) {
  panda::Joints q_true = q;
  for (int j = 0; j < panda::kJointCount; ++j) q_true[static_cast<std::size_t>(j)] += p.joints[j];
  return s.T_camera_base * offset_rigid(p.base) * panda::forward_kinematics(q_true) * offset_rigid(p.mount) *
         s.T_flange_holder;
}

RadialDistortion distortion_of(const DeclaredSetup& s, const EffectParameters& p) {
  RadialDistortion d;
  d.k1_per_px2 = p.distortion[0] / (360.0 * 360.0 * 360.0);
  d.centre_px = Eigen::Vector2d(s.K.u0_px + p.distortion[1], s.K.v0_px + p.distortion[2]);
  return d;
}

Intrinsics intrinsics_of(const DeclaredSetup& s, const EffectParameters& p) {
  Intrinsics K = s.K;
  K.u0_px += p.intrinsics[0];
  K.v0_px += p.intrinsics[1];
  K.fu_px += p.intrinsics[2];
  K.fv_px += p.intrinsics[2] * s.K.fv_px / s.K.fu_px;
  return K;
}

Eigen::Vector3d source_offset_at(const EffectParameters& p, int view) {
  return Eigen::Vector3d(p.drift[0], p.drift[1], 0) * (view / 100.0);
}

}  // namespace ctk

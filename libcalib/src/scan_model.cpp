#include "ctk/calib/scan_model.hpp"

#include <cmath>

namespace ctk {

const char* effect_name(Effect e) {
  switch (e) {
    case Effect::robot_base_frame:
      return "robot_base_frame";
    case Effect::holder_mount:
      return "holder_mount";
    case Effect::joint_offsets:
      return "joint_offsets";
    case Effect::source_drift:
      return "source_drift";
    case Effect::sphere_positions:
      return "sphere_positions";
    case Effect::detector_distortion:
      return "detector_distortion";
    case Effect::detector_intrinsics:
      return "detector_intrinsics";
    case Effect::gravity_load:
      return "gravity_load";
  }
  return "?";
}

bool needs_robot(Effect e) {
  return e == Effect::robot_base_frame || e == Effect::holder_mount || e == Effect::joint_offsets || e == Effect::gravity_load;
}

namespace {
Rigid offset_rigid(const double* p) {
  return make_rigid(rotation_from_vector(Eigen::Vector3d(p[0], p[1], p[2])), Eigen::Vector3d(p[3], p[4], p[5]));
}
}  // namespace

FlangeChain flange_chain(const DeclaredSetup& s, const EffectParameters& p, const panda::Joints& q) {
  panda::Joints q_true = q;
  for (int j = 0; j < panda::kJointCount; ++j) q_true[static_cast<std::size_t>(j)] += p.joints[j];
  const Rigid T_base_flange = panda::forward_kinematics(q_true);
  const Eigen::Matrix<double, 6, 1> load =
      gravity_load_offset<double>(T_base_flange.linear(), s.T_flange_holder.linear().col(2), p.gravity);
  return {s.T_camera_base * offset_rigid(p.base) * T_base_flange,
          offset_rigid(p.mount) * offset_rigid(load.data()) * s.T_flange_holder};
}

Rigid robot_predicted_pose(const DeclaredSetup& s, const EffectParameters& p, const panda::Joints& q) {
  const FlangeChain chain = flange_chain(s, p, q);
  return chain.before_flange * chain.after_flange;
}

Eigen::Matrix<double, 6, 1> flange_deviation(const DeclaredSetup& s, const EffectParameters& p, const panda::Joints& q,
                                             const Rigid& T) {
  const FlangeChain chain = flange_chain(s, p, q);
  const Rigid N = chain.before_flange.inverse() * T * chain.after_flange.inverse();
  Eigen::Matrix<double, 6, 1> x;
  x << rotation_vector(N.linear()), N.translation();
  return x;
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

DeclaredSetup declared_setup(const ScanDescription& scan) {
  DeclaredSetup s;
  s.K = scan.intrinsics();
  s.detector = scan.detector;
  s.holder = *scan.holder;
  s.robot = scan.panda.has_value();
  if (scan.panda) {
    s.T_camera_base = scan.panda->T_camera_base;
    s.T_flange_holder = scan.panda->T_flange_holder;
  }
  s.source_drift_mm_per_100_views = scan.source_drift_mm_per_100_views;
  return s;
}

ScanObservations observe_calibration(const ScanDescription& scan, const ScanCalibration& c) {
  ScanObservations o;
  o.setup = declared_setup(scan);
  double sq = 0;
  int dof = 0;
  for (std::size_t v = 0; v < c.views.size(); ++v) {
    const ViewCalibration& r = c.views[v];
    if (r.status != ViewStatus::ok) continue;
    ViewObservations view;
    view.view = static_cast<int>(v);
    if (scan.panda)
      if (const JointRow* row = scan.panda->joints.find(static_cast<int>(v))) {
        view.joints = row->q;
        for (std::size_t j = 0; j < row->q.size(); ++j) (*view.joints)[j] += scan.panda->joint_offsets_rad[j];
      }
    view.T_calibrated = *r.T_camera_holder;
    view.spheres = r.spheres;
    view.measured_px = r.detected_px;
    for (std::size_t k = 0; k < r.detected_px.size(); ++k) sq += (r.detected_px[k] - r.fitted_px[k]).squaredNorm();
    dof += 2 * static_cast<int>(r.detected_px.size()) - 6;
    o.views.push_back(std::move(view));
  }
  if (dof > 0) o.centre_sigma_px = std::sqrt(sq / dof);
  return o;
}

}  // namespace ctk

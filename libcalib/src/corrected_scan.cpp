// The scan with the diagnosis' accepted effects written into it: what calibrate reads next.
#include "ctk/calib/diagnosis.hpp"
#include "ctk/geom/panda.hpp"

namespace ctk {

ScanDescription corrected_scan(const ScanDescription& scan, const Diagnosis& d) {
  ScanDescription out = scan;
  const EffectParameters& p = d.model;
  auto offset = [](const double* x) {
    return make_rigid(rotation_from_vector(Eigen::Vector3d(x[0], x[1], x[2])), Eigen::Vector3d(x[3], x[4], x[5]));
  };
  for (Effect e : d.accepted) {
    switch (e) {
      case Effect::robot_base_frame:
        out.panda->T_camera_base = scan.panda->T_camera_base * offset(p.base);
        break;
      case Effect::holder_mount:
        out.panda->T_flange_holder = offset(p.mount) * scan.panda->T_flange_holder;
        break;
      case Effect::joint_offsets:
        for (int j = 0; j < panda::kJointCount; ++j) out.panda->joint_offsets_rad[static_cast<std::size_t>(j)] += p.joints[j];
        break;
      case Effect::sphere_positions:
        for (std::size_t k = 0; k < out.holder->spheres_mm.size(); ++k) out.holder->spheres_mm[k] += p.spheres[k];
        break;
      case Effect::detector_intrinsics:
        out.principal_point_px += Eigen::Vector2d(p.intrinsics[0], p.intrinsics[1]);
        out.source_to_detector_mm *= 1.0 + p.intrinsics[2] / scan.intrinsics().fu_px;
        break;
      case Effect::detector_distortion: {
        // The centre is absolute (the declared principal point plus the fitted offset). Found on
        // top of a declared distortion, the k1 add up (the centres are taken as the same).
        const RadialDistortion found = distortion_of(declared_setup(scan), p);
        if (out.distortion)
          out.distortion->k1_per_px2 += found.k1_per_px2;
        else
          out.distortion = found;
        break;
      }
      case Effect::source_drift:
        out.source_drift_mm_per_100_views += Eigen::Vector2d(p.drift[0], p.drift[1]);
        break;
      case Effect::gravity_load:
        break;  // never accepted: the scan format has no place for it
    }
  }
  return out;
}

}  // namespace ctk

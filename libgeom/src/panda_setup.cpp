#include "ctk/geom/panda_setup.hpp"

#include <stdexcept>

namespace ctk {

PandaSetup reference_panda_setup(const Detector& detector, double sdd_mm, double sod_mm, double holder_offset_mm) {
  PandaSetup s;
  s.detector = detector;
  s.principal_point_px = detector.centre_px();
  s.source_to_detector_mm = sdd_mm;
  s.source_to_isocentre_mm = sod_mm;
  s.ready = {0.0, -M_PI / 4, 0.0, -3 * M_PI / 4, 0.0, M_PI / 2, M_PI / 4};
  s.T_flange_holder = make_rigid(Eigen::Matrix3d::Identity(), Eigen::Vector3d(0, 0, holder_offset_mm));
  const Rigid T_base_holder = panda::forward_kinematics(s.ready) * s.T_flange_holder;
  // Camera axes in base coordinates: x = base +x, y (image down) = base -z, z (beam) = base +y.
  Eigen::Matrix3d R_camera_base;
  R_camera_base << 1, 0, 0, 0, 0, -1, 0, 1, 0;
  const Eigen::Vector3d t = Eigen::Vector3d(0, 0, sod_mm) - R_camera_base * T_base_holder.translation();
  s.T_camera_base = make_rigid(R_camera_base, t);
  return s;
}

std::vector<panda::Joints> joint7_orbit(const PandaSetup& setup, int count) {
  if (count <= 0) throw std::invalid_argument("joint7_orbit: count must be positive");
  const auto& limit = panda::joint_limits()[6];
  const double margin = 1e-3;
  const double lo = limit.lower_rad + margin, hi = limit.upper_rad - margin;
  std::vector<panda::Joints> out;
  for (int k = 0; k < count; ++k) {
    panda::Joints q = setup.ready;
    q[6] = count == 1 ? setup.ready[6] : lo + (hi - lo) * k / (count - 1);
    out.push_back(q);
  }
  return out;
}

}  // namespace ctk

#include "ctk/phantoms/robot_trajectory.hpp"

#include <cmath>
#include <sstream>

#include "ctk/geom/trajectory.hpp"
#include "ctk/phantoms/panda_ik.hpp"

namespace ctk {

std::vector<PlannedView> circular_robot_trajectory(const PandaSetup& setup, int count) {
  std::vector<PlannedView> views;
  for (const panda::Joints& q : joint7_orbit(setup, count)) {
    const Rigid T_camera_holder = setup.T_camera_base * panda::forward_kinematics(q) * setup.T_flange_holder;
    views.push_back({T_camera_holder.linear().transpose() * Eigen::Vector3d::UnitZ(), q, ""});
  }
  return views;
}

std::vector<PlannedView> spherical_robot_trajectory(const PandaSetup& setup, const std::vector<Eigen::Vector3d>& directions) {
  static const double rolls_deg[] = {0, 90, 180, 270, 45, 135, 225, 315};
  const Rigid T_base_camera = setup.T_camera_base.inverse();
  const Rigid T_holder_flange = setup.T_flange_holder.inverse();
  std::vector<PlannedView> views;
  panda::Joints previous = setup.ready;
  for (const Eigen::Vector3d& direction : directions) {
    PlannedView view{direction.normalized(), std::nullopt, ""};
    double best_mm = 1e300, best_deg = 1e300;
    for (double roll : rolls_deg) {
      const Eigen::Matrix3d R =
          rotation_about(Eigen::Vector3d::UnitZ(), roll * M_PI / 180) * rotation_looking_along(view.direction);
      const Rigid T_camera_holder = make_rigid(R, Eigen::Vector3d(0, 0, setup.source_to_isocentre_mm));
      const Rigid T_base_flange = T_base_camera * T_camera_holder * T_holder_flange;
      for (const panda::Joints& start : {previous, setup.ready}) {
        const IkSolution ik = solve_panda_ik(T_base_flange, start);
        if (ik.reached) {
          view.joints = ik.q;
          break;
        }
        best_mm = std::min(best_mm, ik.position_error_mm);
        best_deg = std::min(best_deg, ik.rotation_error_deg);
      }
      if (view.joints) break;
    }
    if (view.joints) {
      previous = *view.joints;
    } else {
      std::ostringstream note;
      note << "unreachable within the joint limits at any of 8 rolls about the beam (closest: " << best_mm << " mm, " << best_deg
           << " deg off)";
      view.note = note.str();
    }
    views.push_back(std::move(view));
  }
  return views;
}

}  // namespace ctk

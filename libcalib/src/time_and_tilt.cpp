#include "time_and_tilt.hpp"

#include <Eigen/Dense>
#include <cmath>
#include <vector>

#include "ctk/geom/panda.hpp"

namespace ctk {

TimeAndTilt time_and_tilt(const ScanObservations& o) {
  std::vector<double> time, tilt;
  const Eigen::Vector3d axis = o.setup.T_flange_holder.linear().col(2);
  for (const ViewObservations& v : o.views) {
    if (!v.joints) continue;
    // Gravity (base -z) in the flange frame, then its part across the holder's axis.
    const Eigen::Vector3d g = -panda::forward_kinematics(*v.joints).linear().row(2).transpose();
    time.push_back(v.view);
    tilt.push_back((g - g.dot(axis) * axis).norm());
  }
  if (time.size() < 3) return {};
  const Eigen::Map<const Eigen::VectorXd> t(time.data(), static_cast<Eigen::Index>(time.size())),
      s(tilt.data(), static_cast<Eigen::Index>(tilt.size()));
  const Eigen::VectorXd a = t.array() - t.mean(), b = s.array() - s.mean();
  // A tilt constant to rounding (a joint-7 orbit) has no correlation to speak of.
  if (a.squaredNorm() <= 0 || b.squaredNorm() <= 1e-12 * static_cast<double>(b.size())) return {};
  return {a.dot(b) / (a.norm() * b.norm())};
}

}  // namespace ctk

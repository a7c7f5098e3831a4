#include "time_and_tilt.hpp"

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
  TimeAndTilt t;
  t.views = static_cast<int>(time.size());
  if (t.views < 3) return t;
  const double n = t.views;
  double mt = 0, ms = 0;
  for (int i = 0; i < t.views; ++i) {
    mt += time[static_cast<std::size_t>(i)] / n;
    ms += tilt[static_cast<std::size_t>(i)] / n;
  }
  double stt = 0, sss = 0, sts = 0;
  for (int i = 0; i < t.views; ++i) {
    const double a = time[static_cast<std::size_t>(i)] - mt, b = tilt[static_cast<std::size_t>(i)] - ms;
    stt += a * a;
    sss += b * b;
    sts += a * b;
  }
  // A tilt constant to rounding (a joint-7 orbit) has no correlation to speak of.
  if (stt <= 0 || sss <= 1e-12 * n) return t;
  t.correlation = sts / std::sqrt(stt * sss);
  return t;
}

}  // namespace ctk

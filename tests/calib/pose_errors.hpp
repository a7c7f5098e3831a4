#pragma once
// Calibrated poses against the simulator's truth (truth.json beside the scan).
#include <cmath>
#include <filesystem>

#include "ctk/calib/scan_calibration.hpp"
#include "ctk/core/error.hpp"
#include "ctk/core/json_access.hpp"
#include "ctk/geom/rigid.hpp"

namespace ctk {

struct PoseErrors {
  double across_rms_mm = 0, along_rms_mm = 0, rotation_rms_deg = 0, rotation_max_deg = 0;
};

inline PoseErrors compare_with_truth(const ScanCalibration& c, const std::filesystem::path& dir) {
  const nlohmann::json truth = read_json_file(dir / "truth.json");
  double across = 0, along = 0, rotation = 0;
  PoseErrors e;
  int n = 0;
  for (std::size_t v = 0; v < c.views.size(); ++v) {
    if (c.views[v].status != ViewStatus::ok) continue;
    const JsonNode node(truth.at("views").at(v).at("T_camera_holder"), "truth.json", "T");
    const Rigid T_true = rigid_from_json(node);
    const Rigid& T = *c.views[v].T_camera_holder;
    // Compare where each puts the holder origin (camera frame) and the rotation between them.
    const Eigen::Vector3d d = T.translation() - T_true.translation();
    across += d.head<2>().squaredNorm() / 2;
    along += d.z() * d.z();
    const double angle = rotation_angle_deg(T.linear() * T_true.linear().transpose());
    e.rotation_max_deg = std::max(e.rotation_max_deg, angle);
    rotation += angle * angle;
    ++n;
  }
  e.across_rms_mm = std::sqrt(across / n);
  e.along_rms_mm = std::sqrt(along / n);
  e.rotation_rms_deg = std::sqrt(rotation / n);
  return e;
}

}  // namespace ctk

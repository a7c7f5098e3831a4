#pragma once
// The truth of a simulated scan, drawn once (reproducibly from the seed) before any image is
// made: true holder, true frames and detector, per-view true pose, matrix and image effects.
#include <nlohmann/json.hpp>
#include <optional>
#include <vector>

#include "ctk/phantoms/simulation_config.hpp"

namespace ctk {

struct TrueView {
  int index = 0;
  std::optional<panda::Joints> joints_true;   // robot scans: logged + offsets
  std::optional<Rigid> T_camera_holder;       // in the nominal camera frame (focal spot at rest)
  std::optional<ProjectionMatrix> P;          // absent: the view was not acquired
  Eigen::Vector3d source_offset_mm{0, 0, 0};  // focal-spot drift at this view
  std::optional<Holder> holder;               // the holder of this view when a sphere moves
  double blur_sigma_px = 0;                   // 0: sharp
  std::vector<Blob> blobs;                    // spurious blobs added to the image
  std::string note;                           // why not acquired
};

struct TrueScan {
  Holder holder;                                  // true sphere centres (at the first view when one moves)
  int moving_sphere = -1;                         // the sphere that moves during the scan, if any
  Eigen::Vector3d moving_sphere_end_mm{0, 0, 0};  // its offset at the last view
  Eigen::Matrix3d detector_matrix;                // true K (or tilted-detector matrix), focal spot at rest
  Rigid T_camera_base = Rigid::Identity(), T_flange_holder = Rigid::Identity();
  std::vector<TrueView> views;

  int acquired_views() const;
};

/// Throws std::invalid_argument for inconsistent settings (pose effects on a matrices scan, ...).
TrueScan make_true_scan(const ScanSimulation& simulation);
/// truth.json ("ctk-truth/1"): effects in the diagnosis contract's names and keys, conventions,
/// per-view true poses and joints; the true matrices go to the geometry file it names.
nlohmann::json truth_to_json(const ScanSimulation& simulation, const TrueScan& truth, const std::string& geometry_file);
Geometry true_geometry(const ScanSimulation& simulation, const TrueScan& truth, const std::vector<std::string>& projection_names);

}  // namespace ctk

#pragma once
// The geometry the setup predicts before any image is looked at: for a robot scan, per view
// T_camera_holder = T_camera_base * FK(q) * T_flange_holder and P = K [R | t]; for a
// "matrices" scan, the matrices given.
#include <filesystem>
#include <optional>
#include <vector>

#include "ctk/geom/geometry_file.hpp"
#include "ctk/geom/scan.hpp"

namespace ctk {

struct NominalView {
  std::optional<Rigid> T_camera_holder;  // robot scans only
  std::optional<ProjectionMatrix> P;
  std::string reason;  // why there is no pose (absent joints row, limits)
};

std::vector<NominalView> nominal_views(const ScanDescription& scan);
/// As a geometry file: views with a pose "ok", others "skipped" with the reason.
Geometry nominal_geometry(const ScanDescription& scan);
/// The geometry a run uses: `geometry_file` read when given (binned with the scan when it was made
/// for the stored pixels: geometry_for_scan), else the scan's nominal geometry,
/// which then names `scan_file` as its source in messages.
Geometry geometry_or_nominal(const ScanDescription& scan, const std::filesystem::path& scan_file,
                             const std::filesystem::path& geometry_file);

}  // namespace ctk

#include "ctk/plan/planned_scan.hpp"

#include "ctk/core/atomic_write.hpp"
#include "ctk/core/provenance.hpp"
#include "ctk/geom/scan.hpp"

namespace ctk {

nlohmann::json planned_view_to_json(const PlannedViewRecord& v) {
  nlohmann::json j = {{"request", v.index},
                      {"scout", v.scout},
                      {"direction_holder", {v.requested.x(), v.requested.y(), v.requested.z()}},
                      {"status", v.acquired ? "acquired" : "unreachable"},
                      {"predicted_damage_mm", v.damage_mm},
                      {"planning_seconds", v.planning_seconds}};
  if (!v.reason.empty()) j["reason"] = v.reason;
  if (v.acquired) {
    j["projection"] = v.projection_file;
    j["calibrated"] = v.calibrated;
    if (v.calibrated) j["calibration_rms_px"] = v.calibration_rms_px;
  }
  return j;
}

nlohmann::json trajectory_to_json(const PlanningResult& r) {
  nlohmann::json views = nlohmann::json::array();
  for (const PlannedViewRecord& v : r.views) views.push_back(planned_view_to_json(v));
  return {{"format", "ctk-plan/1"},
          {"provenance", provenance()},
          {"acquired", r.acquired()},
          {"calibrated", r.calibrated()},
          {"requests", r.views.size()},
          {"absorbers",
           {{"voxels", r.segmentation.voxels},
            {"threshold_per_mm", r.segmentation.threshold},
            {"holder_wall_per_mm", r.segmentation.wall_level},
            {"note", r.segmentation.note}}},
          // How the draws were made, so a trajectory can be planned again or told apart.
          {"planner",
           {{"seed", r.planner.seed},
            {"candidate_nside", r.planner.candidate_nside},
            {"planned_views", r.planner.planned_views},
            {"damage_exponent", r.planner.damage_exponent},
            {"spread_exponent", r.planner.spread_exponent},
            {"widest_gap_fraction", r.planner.widest_gap_fraction},
            {"edge_tangency_weight", r.planner.edge_tangency_weight},
            {"tangent_width_deg", r.edge_tangency.tangent_width_deg},
            {"picture_median", r.picture_median},
            {"damage_floor_mm", r.planner.damage_floor_mm},
            {"unreachable_radius_deg", r.planner.unreachable_radius_deg}}},
          {"planning_step_seconds", {{"mean", r.mean_step_seconds()}, {"max", r.max_step_seconds()}}},
          {"views", views}};
}

void write_planned_scan(const PlanningResult& r, const PlanningSetup& s, const std::filesystem::path& folder) {
  ScanDescription scan;
  scan.folder = folder;
  scan.detector = s.setup.detector;
  scan.principal_point_px = s.setup.principal_point_px;
  scan.source_to_detector_mm = s.setup.source_to_detector_mm;
  scan.projections.kind = ProjectionKind::counts;
  scan.projections.flat = {"flat.tif"};
  scan.projections.dark = {"dark.tif"};
  PandaPoseSource panda;
  panda.joints_csv = "joints.csv";
  panda.T_camera_base = s.setup.T_camera_base;
  panda.T_flange_holder = s.setup.T_flange_holder;
  Geometry geometry;
  geometry.detector = s.setup.detector;
  for (const PlannedViewRecord& v : r.views) {
    if (!v.acquired) continue;
    const int index = static_cast<int>(scan.projections.file_names.size());
    scan.projections.file_names.push_back(v.projection_file);
    panda.joints.add(index, v.joints);
    GeometryView g;
    g.index = index;
    g.projection = v.projection_file;
    if (v.calibrated) {
      g.P = v.P;
      g.rms_px = v.calibration_rms_px;
    } else {
      g.status = ViewStatus::rejected;  // reconstruction leaves it out
      g.reason = v.reason;
    }
    geometry.views.push_back(g);
  }
  scan.projections.count = static_cast<int>(scan.projections.file_names.size());
  scan.panda = panda;
  scan.holder = s.holder;
  write_image_uint16(s.flat, folder / "flat.tif");
  write_image_uint16(s.dark, folder / "dark.tif");
  panda.joints.write(folder / "joints.csv");
  write_geometry(geometry, folder / "geometry.json");
  write_text_atomically(folder / "trajectory.json", trajectory_to_json(r).dump(2) + "\n");
  write_scan(scan, folder / "scan.json");
}

}  // namespace ctk

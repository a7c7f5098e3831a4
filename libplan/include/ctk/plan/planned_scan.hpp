#pragma once
// A planned (or compared) trajectory as the files every other command reads: scan.json
// (ctk-scan/1: the declared setup, the acquired views' projections and joints, the open-beam
// frames) and geometry.json (ctk-geometry/1: each view's calibrated matrix), plus trajectory.json
// (ctk-plan/1: every request in order, scout or planned, acquired or refused with the reason, the
// damage predicted when it was chosen and the planner's time).
#include <filesystem>

#include "ctk/plan/plan_trajectory.hpp"

namespace ctk {

/// `folder` must already hold the projections named in the records (relative to it). Writes
/// flat.tif and dark.tif, joints.csv, geometry.json, trajectory.json, then scan.json last.
void write_planned_scan(const PlanningResult& result, const PlanningSetup& setup, const std::filesystem::path& folder);

nlohmann::json trajectory_to_json(const PlanningResult& result);
/// One request as trajectory.json lists it: request, scout, direction_holder, status, reason,
/// projection, calibrated, calibration_rms_px, predicted_damage_mm, planning_seconds.
nlohmann::json planned_view_to_json(const PlannedViewRecord& view);

}  // namespace ctk

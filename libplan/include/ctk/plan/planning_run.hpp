#pragma once
// The planning workflow. A request holds the planner's settings as a person gives them (views,
// scout and candidate resolutions, the exponents, the coarse volume), checked. Lab mode plans
// through request/answer files with the lab's acquisition process and writes the planned scan to a
// folder of its own; the simulated lab's run, with the trajectory comparison, is
// simulated_planning_run.hpp. `ctk plan` and `ctk.plan_lab` wrap it.
#include <cstdint>
#include <filesystem>
#include <functional>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "ctk/geom/scan.hpp"
#include "ctk/plan/plan_trajectory.hpp"

namespace ctk {

struct PlanRequest {
  int views = 100;  // acquired views wanted, scout included
  int scout_nside = 2, candidate_nside = 8;
  double damage_exponent = PlannerOptions{}.damage_exponent;
  double spread_exponent = PlannerOptions{}.spread_exponent;
  double widest_gap_fraction = PlannerOptions{}.widest_gap_fraction;
  double edge_tangency_weight = PlannerOptions{}.edge_tangency_weight;
  double tangent_width_deg = EdgeTangencyOptions{}.tangent_width_deg;
  bool picture_median = PlanningOptions{}.picture_median;  // the coarse picture read through a 3^3 median
  std::uint64_t seed = 1;
  int coarse_size = 128;  // voxels per axis of the planner's volume
  double coarse_voxel_mm = 0.75;
  int binning = 3;        // detector binning of the planner's reconstruction
  void validate() const;  // std::invalid_argument naming the field (PlanRequest.coarse_size, ...)
  /// The loop's options (damage floor two coarse voxels); validated.
  PlanningOptions planning_options() const;
};

/// One trajectory as written: its folder (scan.json, geometry.json, trajectory.json, the
/// projections; a planned one also plan-map.png and coarse.nrrd) and what the loop found.
struct PlanningRun {
  std::string name;  // "planned", "whole-sphere", "random", "random-2", ...
  std::filesystem::path folder;
  PlanningResult result;
  std::vector<std::filesystem::path> pictures;  // those drawn for it: the planner's map
  double seconds = 0;
  /// "<folder>: N views calibrated, M acquired in R requests; planner step ... s mean, ... s max;
  /// absorbers: ..."
  std::string brief() const;
  nlohmann::json report() const;  // trajectory.json's content (ctk-plan/1)
};

/// Writes a trajectory's files into `folder`, which already holds its projections; with `map`
/// the planner's map (plan-map.png) and its coarse volume (coarse.nrrd) too.
PlanningRun write_planning_run(std::string name, const std::filesystem::path& folder, PlanningResult result,
                               const PlanningSetup& setup, bool map, double seconds);

struct LabPlanRequest {
  PlanRequest plan;
  std::filesystem::path lab;    // the folder shared with the acquisition process
  std::filesystem::path setup;  // the lab's ctk-scan/1 file: detector, robot frames, holder, flat, dark
  std::filesystem::path out;    // where the planned scan goes (nothing in `lab` is touched)
  double sod_mm = 1360;         // source to isocentre
  int timeout_s = 600;          // to wait for each answer
  void validate() const;        // std::invalid_argument naming the field
};

/// What the planner is told by a lab's ctk-scan/1 file `file`, with the isocentre distance. Throws
/// InputError naming the file and the key when it has no robot frames, no holder or no flat and dark.
PlanningSetup lab_planning_setup(const std::filesystem::path& file, const ScanDescription& scan, double sod_mm);

/// Plans with the lab through `request.lab` until the trajectory is complete, then writes it to
/// `request.out` naming the lab's images from there. Run again with the same settings it replays
/// the answers already given (acquisition.hpp). Throws InputError for a setup that cannot plan,
/// an output that would overwrite an input, or an answer that does not fit; `on_view` sees every
/// request as it is settled.
PlanningRun run_lab_planning(const LabPlanRequest& request, const std::function<void(const PlannedViewRecord&)>& on_view = {});

}  // namespace ctk

#pragma once
// The planning loop (thesis chapter 7, done better): a scout scan on a coarse HEALPix sphere,
// then view after view: calibrate the new view from its helix spheres (robot FK as first guess),
// add it to the warm-started coarse reconstruction, segment the absorbers, score every candidate
// direction by the absorber path it would look through and by the edges it would graze, and draw
// the next direction (view_planner).
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "ctk/calib/view_calibration.hpp"
#include "ctk/geom/panda_setup.hpp"
#include "ctk/plan/absorber_segmentation.hpp"
#include "ctk/plan/acquisition.hpp"
#include "ctk/plan/direction_damage.hpp"
#include "ctk/plan/edge_tangency.hpp"
#include "ctk/plan/incremental_reconstruction.hpp"
#include "ctk/plan/planner_picture.hpp"
#include "ctk/plan/view_planner.hpp"

namespace ctk {

/// What the planner is told about the setup: the declared geometry and open-beam frames.
struct PlanningSetup {
  PandaSetup setup;
  Holder holder;
  Image flat, dark;  // counts
};

struct PlanningOptions {
  int scout_nside = 2;   // 24 scout directions (one of each opposite pair of 48 cells)
  int views = 100;       // acquired views wanted in all (scout included)
  int max_attempts = 0;  // requests in all; 0: three times `views`
  int request_limit() const { return max_attempts > 0 ? max_attempts : 3 * views; }
  /// Non-empty: no scout and no planning, these directions are requested in order until `views`
  /// are acquired (the trajectories a planned one is compared with).
  std::vector<Eigen::Vector3d> fixed_directions;
  VolumeLayout coarse_volume;
  PlannerOptions planner;
  IncrementalOptions reconstruction;
  SegmentationOptions segmentation;  // its region is also where edges are looked for
  EdgeTangencyOptions edge_tangency;
  bool picture_median = true;  // the coarse picture read through a 3^3 median (picture_median.hpp)
  CalibrationOptions calibration;
  PictureReading picture_reading() const;  // the above as read_planner_picture takes them
  void validate() const;                   // std::invalid_argument naming the field, its own and its parts'
};

struct PlannedViewRecord {
  int index = 0;  // request number (the exchange's view number)
  bool scout = false;
  Eigen::Vector3d requested{0, 0, 1};
  bool acquired = false;    // the lab took the projection
  bool calibrated = false;  // and its spheres fixed the pose: only such views are used
  std::string reason;       // unreachable, or why calibration failed
  panda::Joints joints{};
  std::optional<ProjectionMatrix> P;  // calibrated; absent when calibration failed
  double calibration_rms_px = 0;
  double damage_mm = 0;  // of the requested direction when it was chosen
  std::string projection_file;
  double planning_seconds = 0;  // this view's share of the planner's own work (not acquisition)
};

struct PlanningResult {
  std::vector<PlannedViewRecord> views;
  Volume coarse;
  AbsorberSegmentation segmentation;
  std::vector<Eigen::Vector3d> candidates;
  std::vector<CandidateWeight> weights;  // at the end
  std::vector<double> damage_mm;         // per candidate, at the end
  std::vector<double> step_seconds;      // planner time of each planned (not scout) step
  PlannerOptions planner;                // the settings the draws were made with
  EdgeTangencyOptions edge_tangency;     // and how the edges' demand was found
  bool picture_median = true;            // and whether the picture was read through a median
  int acquired() const;                  // projections taken
  int calibrated() const;                // of those, calibrated: the views of the trajectory
  double mean_step_seconds() const;      // of step_seconds (0 without planned steps)
  double max_step_seconds() const;
};

PlanningResult plan_trajectory(Acquisition& acquisition, const PlanningSetup& setup, const PlanningOptions& options,
                               const std::function<void(const PlannedViewRecord&)>& on_view = {});

/// The directions the planner's rule draws when its picture of the sample is `picture` from the
/// start (damage and edge demand read off it once) and every direction `reachable` allows is taken
/// exactly as requested: no acquisition, no noise, no calibration. A check of the rule apart from
/// how well the coarse reconstruction shows the sample (feed it the truth); the scout comes first,
/// as in plan_trajectory, and `options.coarse_volume` is not used. An empty `reachable` allows all.
std::vector<Eigen::Vector3d> plan_on_picture(const Volume& picture, const PlanningOptions& options,
                                             const DamageGeometry& geometry,
                                             const std::function<bool(const Eigen::Vector3d&)>& reachable = {});

/// The scout's directions: one of each opposite pair of a HEALPix sphere's cells at `nside`
/// (6 nside^2 directions). Opposite views see nearly the same lines, so the pair would spend a
/// view on what the first already measured.
std::vector<Eigen::Vector3d> scout_directions(int nside);
/// The whole sphere in an order whose every prefix is spread evenly: the cells of a HEALPix
/// sphere at `nside`, each next one the farthest (as a line: opposite directions count as one)
/// from those before it.
std::vector<Eigen::Vector3d> whole_sphere_order(int nside);

}  // namespace ctk

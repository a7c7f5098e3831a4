#pragma once
// The planning workflow against the simulated lab (target ctk::plan_simulated): phantoms in the
// holder, a planned trajectory acquired and calibrated view by view, and, to compare, the
// whole-sphere and random trajectories of as many views, each reconstructed alike and scored
// against the voxelised truth (trajectory_quality.hpp). `ctk plan --phantom` and `ctk.plan` wrap it.
#include <filesystem>
#include <functional>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "ctk/phantoms/simulation_config.hpp"
#include "ctk/plan/planning_run.hpp"
#include "ctk/plan/trajectory_quality.hpp"

namespace ctk {

/// How every compared trajectory is reconstructed: WLS-CG on a binned detector, gradient penalty.
struct ComparisonOptions {
  int size = 0;  // voxels per axis of a cube; 0: a volume holding the holder's tube and the sample
  double voxel_mm = 0.5;
  int iterations = 20;
  double lambda = 3.0;
  int binning = 2;
  void validate() const;  // std::invalid_argument naming the field
};

struct SimulatedPlanRequest {
  PlanRequest plan;
  /// Built-in phantom names or ctk-phantom/1 files (.json), placed in the holder.
  std::vector<std::string> phantoms;
  /// The holder: built-in by name (reference, thesis-first) or a ctk-holder/1 file.
  std::string holder = "reference";
  std::filesystem::path out = "plan";  // planned/ and, to compare, whole-sphere/, random/ ...
  int cols = 720, rows = 720;
  double pitch_mm = 0.6, sdd_mm = 2150, sod_mm = 1360;
  double kvp = 90, filter_al_mm = 2.0, flat_counts = 1e4;  // a polychromatic tube, open-beam counts
  bool compare = false;                                    // also acquire and score the whole-sphere and random trajectories
  bool compare_only = false;                               // score the trajectories already in `out` (no acquisition)
  int random_draws = 1;                                    // random trajectories, each a draw of its own
  static constexpr int kMostRandomDraws = 100;
  /// ctk-directions/1 files: trajectories of one's own, acquired and scored beside the others.
  std::vector<std::filesystem::path> compare_directions;
  ComparisonOptions comparison;
  void validate() const;  // std::invalid_argument naming the field
};

// Its implicit move is noexcept (every member's is); clang-tidy reads a throw into nlohmann::json's.
// NOLINTNEXTLINE(bugprone-exception-escape)
struct TrajectoryComparison {
  std::vector<std::string> names;  // planned, whole-sphere, the random draws, then the given lists
  std::vector<TrajectoryQuality> quality;
  int views = 0;                        // the planned trajectory's calibrated views (each other gets as many)
  nlohmann::json report;                // comparison.json (ctk-plan-comparison/1)
  std::filesystem::path file, picture;  // comparison.json and comparison.png
  std::string brief() const;            // "trajectories compared on <sample> (N views each)"
};

struct SimulatedPlanningHooks {
  /// Each request as it is settled, with the trajectory's name and the views it wants.
  std::function<void(const std::string& trajectory, int wanted, const PlannedViewRecord&)> view;
  std::function<void(const std::string&)> log;  // steps: each comparison reconstruction
};

struct SimulatedPlanningRun {
  std::vector<PlanningRun> trajectories;  // planned, then the compared ones (none with compare_only)
  std::optional<TrajectoryComparison> comparison;
  double seconds = 0;
  std::string brief() const;      // each trajectory's brief, then the comparison's
  nlohmann::json report() const;  // {"trajectories": {name: ctk-plan/1}, "comparison": ...}
};

/// The world the request describes: the reference robot setup and holder, the phantoms in it, the
/// tube and the open-beam counts, the seed of the robot's and the photons' noise.
ScanSimulation simulated_world(const SimulatedPlanRequest& request);

/// Throws std::invalid_argument for a request out of range, InputError for a phantom file that
/// cannot be read, an output folder holding an input, or (compare_only) a trajectory missing in `out`.
SimulatedPlanningRun run_simulated_planning(const SimulatedPlanRequest& request, const SimulatedPlanningHooks& hooks = {});

}  // namespace ctk

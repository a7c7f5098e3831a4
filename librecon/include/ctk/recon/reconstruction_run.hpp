#pragma once
// The reconstruction workflow: a volume in the holder frame from a scan's projections and per-view
// matrices, by weighted least squares (CG), SIRT, or FDK for circular scans. The layout and the
// memory plan are decided from the matrices before any image is read, and a run that cannot fit
// is refused then; an iterative run hands its state over for checkpoints and continues from one.
// Spread over the ranks of an MPI run, each rank reads and projects its share of the views and
// holds the whole volume, or holds a slab of the volume and the rows of every view it owns
// (distribution_plan.hpp, docs/distributed.md).
// `ctk reconstruct` and `ctk.reconstruct` wrap it with files.
#include <array>
#include <cstddef>
#include <functional>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "ctk/core/communicator.hpp"
#include "ctk/core/volume.hpp"
#include "ctk/geom/geometry_file.hpp"
#include "ctk/geom/scan.hpp"
#include "ctk/measure/measurements.hpp"
#include "ctk/recon/distribution_plan.hpp"
#include "ctk/recon/fdk.hpp"
#include "ctk/recon/iteration_log.hpp"
#include "ctk/recon/memory_plan.hpp"
#include "ctk/recon/regulariser.hpp"
#include "ctk/recon/solver_state.hpp"
#include "ctk/recon/wls_cg.hpp"

namespace ctk {

struct ReconstructionOptions {
  /// OS-SQS by default: stopped by held-out views, its image had 0.67 to 0.77 times the RMSE of
  /// WLS-CG's in fewer passes, on all 8 cases of bench_stopping_rule (docs/reconstruction-quality.md).
  ReconstructionMethod method = ReconstructionMethod::os_sqs;
  /// 0: the method's default, at most 30 for WLS-CG, 8 epochs for OS-SQS, 100 for SIRT (FDK has
  /// none), ended earlier by `held_out_every`; n > 0: exactly n on every view.
  int iterations = 0;
  /// Default iterations: one view in this many is held out of the solve and the run stops once
  /// their fit stops improving beyond their noise, with the last iterate that improved it
  /// (held_out_fit.hpp). 0, or fewer views: every view is used for the method's default count.
  int held_out_every = 32;
  int subsets = 0;    // OS-SQS: 0 chooses from the view count (default_subset_count)
  double lambda = 0;  // WLS-CG's regularisation weight
  Regulariser regulariser = Regulariser::identity;
  double huber_delta = 0;                     // OS-SQS: > 0 weighs the edge-preserving Huber penalty instead (huber_penalty.hpp)
  double tolerance = WlsOptions{}.tolerance;  // WLS-CG stops when the gradient has fallen by this factor
  CgPreconditioner preconditioner = CgPreconditioner::none;  // WLS-CG: none or diagonal (wls_cg.hpp)
  bool statistical_weights = true;                           // WLS-CG on counts: Poisson weights (line integrals: unit weights)
  bool undistort = true;                                     // a declared detector distortion resampled away (MeasurementOptions)
  std::array<int, 3> size{0, 0, 0};                          // voxels; 0: cover the holder, or the field of view
  double voxel_mm = 0;                                       // 0: a detector pixel seen at the holder origin
  Decomposition decomposition = Decomposition::automatic;    // over several ranks (distribution_plan.hpp)
  void validate() const;                                     // std::invalid_argument naming the field
  int iteration_count() const;                               // `iterations`, or the method's default
  bool stops_on_held_out_views() const;                      // default iterations, ended by held-out views
};

/// OS-SQS's subsets when none are asked for: about 15 views each, at most 24 (12 to 24 subsets of
/// 360 views held their RMSE over 8 epochs, 40 drifted back up: bench_time_to_quality).
int default_subset_count(int views);

/// What a run will do, decided from the matrices alone.
struct ReconstructionPlan {
  ReconstructionMethod method = ReconstructionMethod::wls_cg;
  bool weighted = false;
  VolumeLayout layout;
  int views = 0;                  // ok views of the geometry
  DistributionPlan distribution;  // over the ranks (one rank: views split, nothing exchanged)
  /// Per rank, of the decomposition picked.
  const MemoryPlan& memory() const { return distribution.memory(); }
  std::size_t available_bytes = 0;
};

/// Everything is optional. `resume` receives the run's identity (data fingerprint, views, volume,
/// solver options) and returns a saved state to continue, which must have been saved with the same
/// identity; `save` receives each checkpoint with it.
struct ReconstructionHooks {
  std::function<void(const ReconstructionPlan&)> planned;  // before the memory check and any image
  std::function<void(int, int)> reading;                   // images read, of all
  std::function<void(const Measurements&)> measured;       // after reading, before solving
  std::function<void(int, int)> iterating;                 // iterations done, of all
  std::function<std::optional<SolverState>(const nlohmann::json& identity)> resume;
  int checkpoint_every = 0;  // 0: a state is saved only when a stop is requested
  std::function<void(const SolverSnapshot&, const nlohmann::json& identity)> save;
  std::function<bool()> stop_requested;  // asked after every iteration
};

struct ReconstructionRun {
  Volume volume;
  ReconstructionPlan plan;
  ReconstructionOptions options;
  std::vector<int> views_used;  // scan view indices
  std::size_t clamped_pixels = 0, masked_pixels = 0;
  std::vector<std::string> views_left_out, notes;
  std::string distortion_note;
  std::optional<CircularTrajectory> circle;  // FDK: the orbit fitted to the matrices
  SolverReport solver;
  /// Views held out (ReconstructionOptions::held_out_every): HeldOutFit::report() and their scan
  /// indices ("view_indices"); the volume is the last iterate that improved their fit. Null when
  /// no view was held out.
  nlohmann::json held_out;
  /// Spread over ranks: the bytes this rank handed to the others per iteration, counted (the
  /// median over the iterations), against the plan's model.
  std::size_t counted_bytes_per_iteration = 0;
  std::vector<std::size_t> peak_resident_bytes;  // every rank's, at the end of the run
  double seconds = 0;
  /// Stopped on request (WLS-CG and SIRT with their state saved; OS-SQS after an epoch): the
  /// volume is the last iterate.
  bool stopped() const;
  /// ctk-reconstruction-log/1 without file names (the caller adds scan and geometry).
  nlohmann::json report() const;
  /// One line: method, why it stopped, cost first -> last, seconds.
  std::string brief() const;
};

/// Throws InputError naming the geometry when no view is ok; the options' own errors as validate();
/// std::invalid_argument for FDK over several ranks, or a decomposition that cannot run. The
/// plan is rank `rank`'s (its traffic; the memory is the largest rank's).
ReconstructionPlan plan_reconstruction(const ScanDescription& scan, const Geometry& geometry,
                                       const ReconstructionOptions& options, int ranks = 1, int rank = 0);

/// Plans (refusing a run whose memory plan exceeds what is available, with the plan in the
/// message), reads the ok views, solves. Throws InputError for unreadable images, std::invalid_argument
/// for FDK on a scan that is not circular, with the deviation found. Over several `ranks`, every
/// rank calls it with the same arguments; checkpoints, continuing and stop requests are then not
/// offered (a state would be spread over the ranks), and the hooks see the whole run's numbers.
/// Split into slabs, each rank's `volume` is its slab (slab_layout); the caller writes them in
/// turn (volume_file.hpp's VolumeSlabs), so no rank ever holds the whole volume.
ReconstructionRun run_reconstruction(const ScanDescription& scan, const Geometry& geometry, const ReconstructionOptions& options,
                                     const ReconstructionHooks& hooks = {}, const Communicator& ranks = single_process());

}  // namespace ctk

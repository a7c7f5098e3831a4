// ctk plan: absorption-aware view planning on the sphere. Against the simulator (phantoms in,
// a planned trajectory and its reconstruction out; --compare adds the whole-sphere and the random
// trajectory of the same size, reconstructed alike and scored against the truth), or in lab mode
// through request/answer files with an acquisition process. The workflows are libplan's
// (planning_run.hpp, simulated_planning_run.hpp); this parses, calls and prints.
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <map>
#include <memory>

#include "commands.hpp"
#include "ctk/plan/simulated_planning_run.hpp"
#include "option_checks.hpp"
#include "progress.hpp"
#include "run_page.hpp"

namespace ctk::tools {

namespace {

namespace fs = std::filesystem;

struct PlanCommandOptions {
  SimulatedPlanRequest simulated;  // its plan settings serve lab mode too
  fs::path lab, setup;             // lab mode
  int timeout_s = LabPlanRequest{}.timeout_s;
};

void print_view(const PlannedViewRecord& v, int wanted, int& calibrated) {
  if (v.calibrated) ++calibrated;
  const std::string what = v.calibrated ? "calibrated"
                           : v.acquired ? "left out (" + v.reason + ")"
                                        : "refused (" + v.reason + ")";
  std::fprintf(stderr, "%s request %3d: %s, %d / %d calibrated", v.scout ? "scout" : "plan ", v.index, what.c_str(), calibrated,
               wanted);
  if (v.calibrated) std::fprintf(stderr, ", calibration %.3f px", v.calibration_rms_px);
  if (!v.scout) std::fprintf(stderr, ", predicted absorber path %.1f mm, planner %.2f s", v.damage_mm, v.planning_seconds);
  std::fprintf(stderr, "\n");
}

void report_trajectory(const PlanningRun& r) {
  std::cout << r.brief() << "\n";
  write_and_name_run_page("plan", r.brief(), r.report(), r.pictures, r.folder / "plan.html");
}

void report_comparison(const TrajectoryComparison& c) {
  std::cout << "trajectory      views  RMSE (1/mm)  RMSE outside absorbers  RMSE levels matched  edge gradient (1/mm^2)"
               "  profile gradient (1/mm^2)\n";
  for (std::size_t i = 0; i < c.names.size(); ++i) {
    const TrajectoryQuality& q = c.quality[i];
    std::printf("%-14s %6d  %11.5f  %22.5f  %19.5f  %22.5f  %25.5f\n", c.names[i].c_str(), c.views, q.rmse_per_mm,
                q.rmse_outside_absorbers_per_mm, q.rmse_level_matched_per_mm, q.edge_gradient_per_mm2,
                q.profile_gradient_per_mm2);
  }
  std::printf("truth's edge gradient: %.5f, profile gradient: %.5f\n", c.quality.front().truth_edge_gradient_per_mm2,
              c.quality.front().truth_profile_gradient_per_mm2);
  if (c.quality.size() > 3) std::cout << "random draws: " << c.report["random_draws"].dump() << "\n";
  const fs::path page = fs::path(c.file).replace_extension(".html");
  write_and_name_run_page("plan", c.brief(), c.report, {c.picture}, page);
  std::cout << "comparison written to " << c.file.string() << ", " << c.picture.filename().string() << " and "
            << page.filename().string() << "\n";
}

void run_plan(const PlanCommandOptions& o) {
  if (o.simulated.phantoms.empty() == o.lab.empty())
    throw std::invalid_argument("give either --phantom (simulation) or --lab with --setup (lab mode)");
  if (!o.lab.empty()) {
    if (o.setup.empty()) throw std::invalid_argument("lab mode needs --setup (the lab's ctk-scan/1 file)");
    LabPlanRequest request;
    request.plan = o.simulated.plan;
    request.lab = o.lab;
    request.setup = o.setup;
    request.out = o.simulated.out;
    request.sod_mm = o.simulated.sod_mm;
    request.timeout_s = o.timeout_s;
    int calibrated = 0;
    const PlanningRun r =
        run_lab_planning(request, [&](const PlannedViewRecord& v) { print_view(v, request.plan.views, calibrated); });
    report_trajectory(r);
    return;
  }
  SimulatedPlanningHooks hooks;
  int planned_calibrated = 0;
  std::map<std::string, std::pair<std::unique_ptr<Progress>, int>> others;  // progress and views calibrated
  hooks.view = [&](const std::string& trajectory, int wanted, const PlannedViewRecord& v) {
    if (trajectory == "planned") return print_view(v, wanted, planned_calibrated);
    auto& [progress, calibrated] = others[trajectory];
    if (!progress) progress = std::make_unique<Progress>(trajectory + " trajectory", "views calibrated");
    if (v.calibrated) (*progress)(++calibrated, wanted);
  };
  hooks.log = [](const std::string& line) { std::cerr << line << " ...\n"; };
  const SimulatedPlanningRun run = run_simulated_planning(o.simulated, hooks);
  for (const PlanningRun& r : run.trajectories) report_trajectory(r);
  if (run.comparison) report_comparison(*run.comparison);
  if (!o.simulated.compare_only) std::cout << run.seconds << " s\n";
}

}  // namespace

// NOLINTNEXTLINE(readability-function-size): one statement per option, in the order --help lists them
void register_plan(CLI::App& app) {
  auto o = std::make_shared<PlanCommandOptions>();
  CLI::App* cmd =
      app.add_subcommand("plan", "Plan a spherical trajectory that avoids looking through absorbers (simulation or lab)");
  cmd->add_option("--out", o->simulated.out,
                  "Output folder: the planned scan (lab mode), or planned/ and, with --compare, whole-sphere/ and random/")
      ->capture_default_str();
  cmd->add_option("--phantom", o->simulated.phantoms, "Simulation mode: built-in phantoms or ctk-phantom/1 files in the holder");
  cmd->add_option("--holder", o->simulated.holder,
                  "Simulation mode: the holder (reference, thesis-first, or a ctk-holder/1 file)")
      ->capture_default_str();
  cmd->add_option("--lab", o->lab, "Lab mode: the folder shared with the acquisition process (request/answer files)");
  cmd->add_option("--setup", o->setup, "Lab mode: the lab's ctk-scan/1 file (detector, robot frames, holder, flat, dark)")
      ->check(CLI::ExistingFile);
  cmd->add_option("--timeout", o->timeout_s, "Lab mode: seconds to wait for each answer")
      ->check(positive_number)
      ->capture_default_str();
  cmd->add_option("--sod", o->simulated.sod_mm, "Source-to-isocentre distance (mm)")
      ->check(positive_number)
      ->capture_default_str();
  cmd->add_option("--views", o->simulated.plan.views, "Views to acquire, scout included")
      ->check(CLI::Range(2, 10000))
      ->capture_default_str();
  cmd->add_option("--scout-nside", o->simulated.plan.scout_nside,
                  "HEALPix resolution of the scout (6 nside^2 directions: one of each opposite pair of cells)")
      ->check(CLI::Range(1, 16))
      ->capture_default_str();
  cmd->add_option("--candidate-nside", o->simulated.plan.candidate_nside, "HEALPix resolution of the candidate directions")
      ->check(CLI::Range(1, 64))
      ->capture_default_str();
  cmd->add_option("--spread-exponent", o->simulated.plan.spread_exponent,
                  "m: how strongly the largest gaps between views are preferred")
      ->check(non_negative_number)
      ->capture_default_str();
  cmd->add_option("--widest-gap-fraction", o->simulated.plan.widest_gap_fraction,
                  "f: draw only among directions whose gap to the views so far is at least f times the widest (0: all)")
      ->check(CLI::Range(0.0, 1.0))
      ->capture_default_str();
  cmd->add_option("--edge-tangency-weight", o->simulated.plan.edge_tangency_weight,
                  "b: share of the view density that follows the directions tangent to the sample's strong edges (0: even)")
      ->check(CLI::Range(0.0, 1.0))
      ->capture_default_str();
  cmd->add_option("--tangent-width", o->simulated.plan.tangent_width_deg,
                  "How far from an edge's tangent plane a direction still counts as grazing it (deg)")
      ->check(CLI::Range(1.0, 45.0))
      ->capture_default_str();
  cmd->add_option("--picture-median", o->simulated.plan.picture_median,
                  "Read the planner's coarse picture through a 3x3x3 median (its noise and thin streaks out) before its "
                  "absorbers and edges (true or false)")
      ->capture_default_str();
  cmd->add_option("--damage-exponent", o->simulated.plan.damage_exponent, "s: how strongly long absorber paths are avoided")
      ->check(non_negative_number)
      ->capture_default_str();
  cmd->add_option("--seed", o->simulated.plan.seed, "Seed of the planner's draws (and of the simulation)")->capture_default_str();
  cmd->add_option("--cols", o->simulated.cols, "Simulated detector columns")
      ->check(CLI::Range(16, 100000))
      ->capture_default_str();
  cmd->add_option("--rows", o->simulated.rows, "Simulated detector rows")->check(CLI::Range(16, 100000))->capture_default_str();
  cmd->add_option("--pitch", o->simulated.pitch_mm, "Simulated pixel pitch (mm)")->check(positive_number)->capture_default_str();
  cmd->add_option("--sdd", o->simulated.sdd_mm, "Simulated source-to-detector distance (mm)")
      ->check(positive_number)
      ->capture_default_str();
  cmd->add_option("--kvp", o->simulated.kvp, "Simulated tube voltage (polychromatic)")
      ->check(CLI::Range(16.0, 150.0))
      ->capture_default_str();
  cmd->add_option("--filter-al-mm", o->simulated.filter_al_mm, "Simulated aluminium filter")
      ->check(non_negative_number)
      ->capture_default_str();
  cmd->add_option("--flat-counts", o->simulated.flat_counts, "Simulated open-beam counts")
      ->check(CLI::Range(1.0, 65000.0))
      ->capture_default_str();
  cmd->add_option("--coarse-size", o->simulated.plan.coarse_size, "Voxels per axis of the planner's volume")
      ->check(CLI::Range(8, 1024))
      ->capture_default_str();
  cmd->add_option("--coarse-voxel", o->simulated.plan.coarse_voxel_mm, "Voxel size of the planner's volume (mm)")
      ->check(positive_number)
      ->capture_default_str();
  cmd->add_option("--binning", o->simulated.plan.binning, "Detector binning of the planner's reconstruction")
      ->check(CLI::Range(1, 64))
      ->capture_default_str();
  cmd->add_flag("--compare", o->simulated.compare,
                "Simulation mode: also acquire and reconstruct the whole-sphere and random trajectories of the same size");
  cmd->add_option("--random-draws", o->simulated.random_draws,
                  "With --compare: random trajectories to compare with (random/, random-2/ ...), summarised by mean and range")
      ->check(CLI::Range(1, SimulatedPlanRequest::kMostRandomDraws))
      ->capture_default_str();
  cmd->add_option("--compare-directions", o->simulated.compare_directions,
                  "With --compare or --compare-only: ctk-directions/1 files, trajectories of one's own scored beside the others")
      ->check(CLI::ExistingFile);
  cmd->add_option("--eval-size", o->simulated.comparison.size,
                  "Voxels per axis of a cube for the comparison reconstructions (0: a volume holding the holder and the sample)")
      ->check(CLI::Range(0, 2048))
      ->capture_default_str();
  cmd->add_option("--eval-voxel", o->simulated.comparison.voxel_mm, "Voxel size of the comparison reconstructions (mm)")
      ->check(positive_number)
      ->capture_default_str();
  cmd->add_option("--eval-iterations", o->simulated.comparison.iterations, "WLS-CG iterations of the comparison reconstructions")
      ->check(CLI::Range(1, 1000))
      ->capture_default_str();
  cmd->add_option("--eval-lambda", o->simulated.comparison.lambda, "Gradient penalty of the comparison reconstructions")
      ->check(non_negative_number)
      ->capture_default_str();
  cmd->add_flag("--compare-only", o->simulated.compare_only,
                "Reconstruct and compare the trajectories already in --out (no acquisition)");
  cmd->add_option("--eval-binning", o->simulated.comparison.binning, "Detector binning of the comparison reconstructions")
      ->check(CLI::Range(1, 64))
      ->capture_default_str();
  cmd->callback([o] { run_plan(*o); });
}

}  // namespace ctk::tools

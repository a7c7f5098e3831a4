// ctk plan: absorption-aware view planning on the sphere. Against the simulator (phantoms in,
// a planned trajectory and its reconstruction out; --compare adds the whole-sphere and the random
// trajectory of the same size, reconstructed alike and scored against the truth), or in lab mode
// through request/answer files with an acquisition process (libplan/acquisition.hpp).
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <sstream>

#include "commands.hpp"
#include "ctk/geom/run_files.hpp"
#include "option_checks.hpp"
#include "ctk/core/atomic_write.hpp"
#include "ctk/core/volume_file.hpp"
#include "ctk/geom/scan.hpp"
#include "ctk/geom/trajectory.hpp"
#include "ctk/phantoms/builtin_phantoms.hpp"
#include "ctk/phantoms/render.hpp"
#include "ctk/plan/simulated_acquisition.hpp"
#include "ctk/plan/plan_pictures.hpp"
#include "ctk/plan/planned_scan.hpp"
#include "ctk/core/parallel.hpp"
#include "ctk/proj/projection_reading.hpp"
#include "ctk/recon/measurements.hpp"
#include "ctk/recon/wls_cg.hpp"
#include "ctk/core/provenance.hpp"
#include "progress.hpp"
#include "ctk/core/json_access.hpp"
#include "run_page.hpp"

namespace ctk::tools {

namespace {

namespace fs = std::filesystem;

struct PlanCommandOptions {
  fs::path out = "plan";
  std::vector<std::string> phantoms;  // simulation mode
  fs::path lab, setup;                // lab mode
  double sod_mm = 1360;
  int views = 100, scout_nside = 2, candidate_nside = 8;
  double damage_exponent = PlannerOptions{}.damage_exponent;
  double spread_exponent = PlannerOptions{}.spread_exponent;
  double widest_gap_fraction = PlannerOptions{}.widest_gap_fraction;
  double edge_tangency_weight = PlannerOptions{}.edge_tangency_weight;
  double tangent_width_deg = EdgeTangencyOptions{}.tangent_width_deg;
  std::uint64_t seed = 1;
  int cols = 720, rows = 720;
  double pitch_mm = 0.6, sdd_mm = 2150;
  double kvp = 90, filter_al_mm = 2.0, flat_counts = 1e4;
  int coarse_size = 128;
  double coarse_voxel_mm = 0.75;
  int binning = 3;
  bool compare = false;
  int random_draws = 1;                                       // random trajectories compared (each a draw of its own)
  int eval_size = 0, eval_iterations = 20, eval_binning = 2;  // eval_size 0: everything in the beam
  double eval_voxel_mm = 0.5, eval_lambda = 3.0;
  bool compare_only = false;
  int timeout_s = 600;
};

PlanningOptions planning_options(const PlanCommandOptions& o) {
  PlanningOptions p;
  p.scout_nside = o.scout_nside;
  p.views = o.views;
  p.coarse_volume =
      VolumeLayout::centred({o.coarse_size, o.coarse_size, o.coarse_size}, Eigen::Vector3d::Constant(o.coarse_voxel_mm));
  p.planner.candidate_nside = o.candidate_nside;
  p.planner.planned_views = o.views;
  p.planner.damage_exponent = o.damage_exponent;
  p.planner.spread_exponent = o.spread_exponent;
  p.planner.widest_gap_fraction = o.widest_gap_fraction;
  p.planner.edge_tangency_weight = o.edge_tangency_weight;
  p.edge_tangency.tangent_width_deg = o.tangent_width_deg;
  p.planner.damage_floor_mm = 2 * o.coarse_voxel_mm;
  p.planner.seed = o.seed;
  p.reconstruction.binning = o.binning;
  return p;
}

ScanSimulation simulation_from(const PlanCommandOptions& o) {
  ScanSimulation sim;
  const Detector detector{o.cols, o.rows, o.pitch_mm, o.pitch_mm};
  sim.setup = reference_panda_setup(detector, o.sdd_mm, o.sod_mm);
  sim.holder = reference_helix_holder();
  for (const std::string& name : o.phantoms) {
    const Phantom p = fs::path(name).extension() == ".json" ? read_phantom(name) : builtin_phantom(name);
    sim.sample.name += (sim.sample.name.empty() ? "" : " + ") + p.name;
    sim.sample.add(p);
  }
  sim.spectrum = tube_spectrum(o.kvp, o.filter_al_mm);
  sim.counts = {o.flat_counts, 100};
  sim.seed = o.seed;
  return sim;
}

// Lab mode: the declared setup comes from a ctk-scan/1 file of the lab (detector, frames, holder,
// flat and dark); the isocentre distance from the command line.
PlanningSetup setup_from_scan(const fs::path& file, const ScanDescription& scan, double sod_mm) {
  if (!scan.panda) throw InputError(file.string(), "pose_source", "lab mode needs a panda pose source (the robot's frames)");
  if (!scan.holder) throw InputError(file.string(), "holder", "lab mode calibrates every view: the holder is required");
  const std::optional<FlatDark> fd = read_flat_dark(scan);
  if (!fd) throw InputError(file.string(), "projections.flat", "lab mode needs counts with flat and dark frames");
  PlanningSetup s;
  s.setup.detector = scan.detector;
  s.setup.principal_point_px = scan.principal_point_px;
  s.setup.source_to_detector_mm = scan.source_to_detector_mm;
  s.setup.source_to_isocentre_mm = sod_mm;
  s.setup.T_camera_base = scan.panda->T_camera_base;
  s.setup.T_flange_holder = scan.panda->T_flange_holder;
  s.holder = *scan.holder;
  s.flat = fd->flat;
  s.dark = fd->dark;
  return s;
}

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

// `pictures`: those the run drew for this trajectory (the planner's map; none for the others).
void report_plan(const PlanningResult& r, const fs::path& folder, const std::vector<fs::path>& pictures = {}) {
  double worst = 0, sum = 0;
  for (double s : r.step_seconds) {
    worst = std::max(worst, s);
    sum += s;
  }
  std::ostringstream brief;
  brief << folder.string() << ": " << r.calibrated() << " views calibrated, " << r.acquired() << " acquired in " << r.views.size()
        << " requests";
  if (!r.step_seconds.empty())
    brief << "; planner step " << sum / static_cast<double>(r.step_seconds.size()) << " s mean, " << worst << " s max";
  brief << "; absorbers: "
        << (r.segmentation.voxels > 0 ? std::to_string(r.segmentation.voxels) + " coarse voxels" : r.segmentation.note);
  std::cout << brief.str() << "\n";
  write_run_page("plan", brief.str(), read_json_file(folder / "trajectory.json"), pictures, folder / "plan.html");
}

// The comparison's volume holds everything in the beam: the holder's tube (118 mm tall) and the
// sample. What sticks out of a reconstruction volume is smeared into it by the views that look
// along it, so a cube around the sample alone (80 mm) scored trajectories by
// how often they looked along the tube: on the walnut, random draws of 100 views ranged from
// 0.0043 to 0.0049 in RMSE, the difference all in the 10 mm at each end of the cube.
// --eval-size N asks for an N^3 cube instead.
VolumeLayout evaluation_layout(const PlanCommandOptions& o, const ScanSimulation& simulation) {
  const Eigen::Vector3d voxel = Eigen::Vector3d::Constant(o.eval_voxel_mm);
  if (o.eval_size > 0) return VolumeLayout::centred({o.eval_size, o.eval_size, o.eval_size}, voxel);
  Eigen::Vector3d reach = Eigen::Vector3d::Zero();
  for (const Phantom& p : {helix_holder_phantom(simulation.holder), simulation.sample})
    for (const Primitive& primitive : p.primitives)
      for (const Eigen::Vector3d& corner : primitive.bounding_corners()) reach = reach.cwiseMax(corner.cwiseAbs());
  std::array<int, 3> size{};
  for (int a = 0; a < 3; ++a)
    size[static_cast<std::size_t>(a)] = 2 * static_cast<int>(std::ceil(reach[a] / o.eval_voxel_mm + 0.5));
  return VolumeLayout::centred(size, voxel);
}

// Every trajectory gets the same reconstruction: WLS-CG on a binned detector, gradient penalty.
Volume evaluation_reconstruction(const fs::path& folder, const VolumeLayout& layout, const PlanCommandOptions& o) {
  const ScanDescription scan = read_scan(folder / "scan.json");
  const Geometry geometry = read_geometry(folder / "geometry.json");
  const Measurements m = load_measurements(scan, geometry);
  IncrementalOptions io;
  io.binning = o.eval_binning;
  io.first_update_iterations = o.eval_iterations;
  io.lambda = o.eval_lambda;
  IncrementalReconstruction recon(layout, scan.detector, io);
  const Detector& d = scan.detector;
  for (int v = 0; v < m.line_integrals.views; ++v) {
    const std::size_t n = m.line_integrals.pixels_per_view();
    Image p{d.cols, d.rows, std::vector<float>(m.line_integrals.view(v), m.line_integrals.view(v) + n)};
    Image w{d.cols, d.rows, std::vector<float>(m.weights.view(v), m.weights.view(v) + n)};
    recon.add_view(m.matrices[static_cast<std::size_t>(v)], p, w);
  }
  recon.update();
  write_volume(recon.volume(), folder / "volume.nrrd");
  return recon.volume();
}

// The folder of the k-th random trajectory (k from 0): random/, random-2/, random-3/ ...
std::string random_name(int k) { return k == 0 ? "random" : "random-" + std::to_string(k + 1); }

// The whole-sphere and the random trajectories with as many views as the planned one. Each gets a
// lab of its own, so its n-th shot draws the same robot and photon noise as the planned one's n-th
// shot, whatever the planned run asked before (the comparison does not drift with the planner).
void acquire_others(const PlanCommandOptions& o, const ScanSimulation& simulation, const PlanningSetup& setup, int n) {
  struct Run {
    std::string name;
    std::vector<Eigen::Vector3d> order;
  };
  std::vector<Run> others = {{"whole-sphere", whole_sphere_order(o.candidate_nside)}};
  for (int k = 0; k < o.random_draws; ++k)
    others.push_back({random_name(k), random_directions(6 * n, o.seed + 17 + static_cast<std::uint64_t>(k))});
  for (const Run& run : others) {
    PlanningOptions p = planning_options(o);
    p.views = n;
    p.fixed_directions = run.order;
    p.max_attempts = static_cast<int>(run.order.size());
    SimulatedLab lab(simulation);
    SimulatedAcquisition acquisition(lab, o.out / run.name);
    Progress progress(run.name + " trajectory", "views calibrated");
    int calibrated = 0;
    const PlanningResult r = plan_trajectory(acquisition, setup, p, [&](const PlannedViewRecord& v) {
      if (v.calibrated) progress(++calibrated, n);
    });
    write_planned_scan(r, setup, o.out / run.name);
    report_plan(r, o.out / run.name);
  }
}

// One random trajectory is a lottery (on sample 2, six draws of 100 views ranged from 0.00199 to
// 0.00223 in RMSE), so with several draws the planned one is also set against their spread: each
// figure's mean, least and greatest, and how many draws did better than the planned trajectory.
// `compared` holds the planned trajectory, the whole sphere, then the random draws.
nlohmann::json random_draw_summary(const std::vector<ComparedTrajectory>& compared) {
  nlohmann::json summary = {{"count", compared.size() - 2}};
  const TrajectoryQuality& planned = compared.front().quality;
  auto figure = [&](const char* key, double TrajectoryQuality::*member, bool lower_is_better) {
    double sum = 0, least = 1e300, most = -1e300;
    int better = 0;
    for (std::size_t i = 2; i < compared.size(); ++i) {
      const double v = compared[i].quality.*member;
      sum += v;
      least = std::min(least, v);
      most = std::max(most, v);
      if (lower_is_better ? v < planned.*member : v > planned.*member) ++better;
    }
    summary[key] = {{"mean", sum / static_cast<double>(compared.size() - 2)},
                    {"min", least},
                    {"max", most},
                    {"draws_better_than_planned", better}};
  };
  figure("rmse_per_mm", &TrajectoryQuality::rmse_per_mm, true);
  figure("rmse_outside_absorbers_per_mm", &TrajectoryQuality::rmse_outside_absorbers_per_mm, true);
  figure("edge_gradient_per_mm2", &TrajectoryQuality::edge_gradient_per_mm2, false);
  figure("profile_gradient_per_mm2", &TrajectoryQuality::profile_gradient_per_mm2, false);
  return summary;
}

void compare(const PlanCommandOptions& o, const ScanSimulation& simulation) {
  const Phantom& sample = simulation.sample;
  const int n = read_scan(o.out / "planned" / "scan.json").projections.count;
  const VolumeLayout layout = evaluation_layout(o, simulation);
  const Volume truth = voxelised(sample, layout);
  write_volume(truth, o.out / "truth.nrrd");
  const SampleRegion region;
  const std::array<int, 3> through = centre_of_mass_voxel(truth, region);
  // Absorbers in the truth by the planner's own rule: more than times_wall the holder's wall.
  const float absorber_above = static_cast<float>(SegmentationOptions{}.times_wall * material::pom);
  std::vector<Volume> volumes;
  std::vector<std::string> names = {"planned", "whole-sphere"};
  for (int k = 0; k < o.random_draws; ++k) names.push_back(random_name(k));
  for (const std::string& name : names) {
    std::cerr << "reconstructing " << name << " (" << layout.size[0] << " x " << layout.size[1] << " x " << layout.size[2]
              << " at " << o.eval_voxel_mm << " mm, " << o.eval_iterations << " WLS-CG iterations) ...\n";
    volumes.push_back(evaluation_reconstruction(o.out / name, layout, o));
  }
  std::vector<ComparedTrajectory> compared;
  nlohmann::json table = nlohmann::json::object();
  std::cout << "trajectory      views  RMSE (1/mm)  RMSE outside absorbers  edge gradient (1/mm^2)  profile gradient (1/mm^2)\n";
  for (std::size_t i = 0; i < names.size(); ++i) {
    const TrajectoryQuality q = trajectory_quality(volumes[i], truth, region, through, absorber_above);
    compared.push_back({names[i], &volumes[i], q});
    table[names[i]] = {{"views", n},
                       {"rmse_per_mm", q.rmse_per_mm},
                       {"rmse_outside_absorbers_per_mm", q.rmse_outside_absorbers_per_mm},
                       {"edge_gradient_per_mm2", q.edge_gradient_per_mm2},
                       {"profile_gradient_per_mm2", q.profile_gradient_per_mm2}};
    std::printf("%-14s %6d  %11.5f  %22.5f  %22.5f  %25.5f\n", names[i].c_str(), n, q.rmse_per_mm,
                q.rmse_outside_absorbers_per_mm, q.edge_gradient_per_mm2, q.profile_gradient_per_mm2);
  }
  std::printf("truth's edge gradient: %.5f, profile gradient: %.5f\n", compared.front().quality.truth_edge_gradient_per_mm2,
              compared.front().quality.truth_profile_gradient_per_mm2);
  const nlohmann::json draws = random_draw_summary(compared);
  if (o.random_draws > 1) std::cout << "random draws: " << draws.dump() << "\n";
  compared.resize(3);  // the picture shows planned, whole sphere and the first random draw
  write_trajectory_comparison_png(compared, truth, o.out / "comparison.png");
  nlohmann::json j = {{"format", "ctk-plan-comparison/1"},
                      {"provenance", provenance()},
                      {"sample", sample.name},
                      {"volume",
                       {{"size", layout.size},
                        {"voxel_mm", o.eval_voxel_mm},
                        {"iterations", o.eval_iterations},
                        {"lambda", o.eval_lambda},
                        {"binning", o.eval_binning}}},
                      {"profile_through_voxel", through},
                      {"absorbers_above_per_mm", absorber_above},
                      {"truth_edge_gradient_per_mm2", compared.front().quality.truth_edge_gradient_per_mm2},
                      {"truth_profile_gradient_per_mm2", compared.front().quality.truth_profile_gradient_per_mm2},
                      {"trajectories", table},
                      {"random_draws", draws}};
  // The acquisition's settings are known only when this run acquired (not with --compare-only).
  if (!o.compare_only) {
    j["spectrum"] = {{"kvp", o.kvp}, {"filter_al_mm", o.filter_al_mm}};
    j["flat_counts"] = o.flat_counts;
  }
  write_text_atomically(o.out / "comparison.json", j.dump(2) + "\n");
  write_run_page("plan", "trajectories compared on " + sample.name + " (" + std::to_string(n) + " views each)", j,
                 {o.out / "comparison.png"}, o.out / "comparison.html");
  std::cout << "comparison written to " << (o.out / "comparison.json").string() << ", comparison.png and comparison.html\n";
}

void run_plan(const PlanCommandOptions& o) {
  const auto start = std::chrono::steady_clock::now();
  if (o.phantoms.empty() == o.lab.empty())
    throw std::invalid_argument("give either --phantom (simulation) or --lab with --setup (lab mode)");
  const PlanningOptions options = planning_options(o);
  int calibrated = 0;
  auto on_view = [&](const PlannedViewRecord& v) { print_view(v, o.views, calibrated); };
  if (!o.lab.empty()) {
    if (o.setup.empty()) throw std::invalid_argument("lab mode needs --setup (the lab's ctk-scan/1 file)");
    const ScanDescription lab_scan = read_scan(o.setup);
    RunFiles files;
    files.scan("--setup", o.setup, lab_scan);
    files.input_folder("--lab", o.lab);
    for (const char* name : {"scan.json", "joints.csv", "flat.tif", "dark.tif", "geometry.json", "trajectory.json",
                             "plan-map.png", "coarse.nrrd", "plan.html"})
      files.output(std::string("--out: ") + name, o.out / name);
    files.check();
    const PlanningSetup setup = setup_from_scan(o.setup, lab_scan, o.sod_mm);
    FileExchangeAcquisition acquisition(o.lab, setup.setup.detector.cols, setup.setup.detector.rows,
                                        std::chrono::seconds(o.timeout_s));
    PlanningResult r = plan_trajectory(acquisition, setup, options, on_view);
    acquisition.finish();
    // The lab's folder is its own: the planned scan goes to --out and names the lab's images
    // from there, so nothing the lab wrote is touched.
    fs::create_directories(o.out);
    for (PlannedViewRecord& v : r.views)
      if (v.acquired) v.projection_file = fs::relative(fs::absolute(o.lab / v.projection_file), fs::absolute(o.out)).string();
    write_planned_scan(r, setup, o.out);
    write_plan_map_png(r, o.out / "plan-map.png");
    write_volume(r.coarse, o.out / "coarse.nrrd");
    report_plan(r, o.out, {o.out / "plan-map.png"});
    return;
  }
  RunFiles files;
  for (const std::string& name : o.phantoms)
    if (fs::path(name).extension() == ".json") files.input("--phantom", name);
  files.output_folder("--out", o.out);
  files.check();
  if (o.compare_only) {
    compare(o, simulation_from(o));
    return;
  }
  SimulatedLab lab(simulation_from(o));
  const PlanningSetup setup = planning_setup(lab.simulation());
  const fs::path folder = o.out / "planned";
  SimulatedAcquisition acquisition(lab, folder);
  const PlanningResult r = plan_trajectory(acquisition, setup, options, on_view);
  write_planned_scan(r, setup, folder);
  write_plan_map_png(r, folder / "plan-map.png");
  write_volume(r.coarse, folder / "coarse.nrrd");
  report_plan(r, folder, {folder / "plan-map.png"});
  if (o.compare) {
    acquire_others(o, lab.simulation(), setup, r.calibrated());
    compare(o, lab.simulation());
  }
  std::cout << std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count() << " s\n";
}

}  // namespace

void register_plan(CLI::App& app) {
  auto o = std::make_shared<PlanCommandOptions>();
  CLI::App* cmd =
      app.add_subcommand("plan", "Plan a spherical trajectory that avoids looking through absorbers (simulation or lab)");
  cmd->add_option("--out", o->out,
                  "Output folder: the planned scan (lab mode), or planned/ and, with --compare, whole-sphere/ and random/")
      ->capture_default_str();
  cmd->add_option("--phantom", o->phantoms, "Simulation mode: built-in phantoms or ctk-phantom/1 files in the holder");
  cmd->add_option("--lab", o->lab, "Lab mode: the folder shared with the acquisition process (request/answer files)");
  cmd->add_option("--setup", o->setup, "Lab mode: the lab's ctk-scan/1 file (detector, robot frames, holder, flat, dark)")
      ->check(CLI::ExistingFile);
  cmd->add_option("--timeout", o->timeout_s, "Lab mode: seconds to wait for each answer")
      ->check(positive_number)
      ->capture_default_str();
  cmd->add_option("--sod", o->sod_mm, "Source-to-isocentre distance (mm)")->check(positive_number)->capture_default_str();
  cmd->add_option("--views", o->views, "Views to acquire, scout included")->check(CLI::Range(2, 10000))->capture_default_str();
  cmd->add_option("--scout-nside", o->scout_nside,
                  "HEALPix resolution of the scout (6 nside^2 directions: one of each opposite pair of cells)")
      ->check(CLI::Range(1, 16))
      ->capture_default_str();
  cmd->add_option("--candidate-nside", o->candidate_nside, "HEALPix resolution of the candidate directions")
      ->check(CLI::Range(1, 64))
      ->capture_default_str();
  cmd->add_option("--spread-exponent", o->spread_exponent, "m: how strongly the largest gaps between views are preferred")
      ->check(non_negative_number)
      ->capture_default_str();
  cmd->add_option("--widest-gap-fraction", o->widest_gap_fraction,
                  "f: draw only among directions whose gap to the views so far is at least f times the widest (0: all)")
      ->check(CLI::Range(0.0, 1.0))
      ->capture_default_str();
  cmd->add_option("--edge-tangency-weight", o->edge_tangency_weight,
                  "b: share of the view density that follows the directions tangent to the sample's strong edges (0: even)")
      ->check(CLI::Range(0.0, 1.0))
      ->capture_default_str();
  cmd->add_option("--tangent-width", o->tangent_width_deg,
                  "How far from an edge's tangent plane a direction still counts as grazing it (deg)")
      ->check(CLI::Range(1.0, 45.0))
      ->capture_default_str();
  cmd->add_option("--damage-exponent", o->damage_exponent, "s: how strongly long absorber paths are avoided")
      ->check(non_negative_number)
      ->capture_default_str();
  cmd->add_option("--seed", o->seed, "Seed of the planner's draws (and of the simulation)")->capture_default_str();
  cmd->add_option("--cols", o->cols, "Simulated detector columns")->check(CLI::Range(16, 100000))->capture_default_str();
  cmd->add_option("--rows", o->rows, "Simulated detector rows")->check(CLI::Range(16, 100000))->capture_default_str();
  cmd->add_option("--pitch", o->pitch_mm, "Simulated pixel pitch (mm)")->check(positive_number)->capture_default_str();
  cmd->add_option("--sdd", o->sdd_mm, "Simulated source-to-detector distance (mm)")
      ->check(positive_number)
      ->capture_default_str();
  cmd->add_option("--kvp", o->kvp, "Simulated tube voltage (polychromatic)")
      ->check(CLI::Range(16.0, 150.0))
      ->capture_default_str();
  cmd->add_option("--filter-al-mm", o->filter_al_mm, "Simulated aluminium filter")
      ->check(non_negative_number)
      ->capture_default_str();
  cmd->add_option("--flat-counts", o->flat_counts, "Simulated open-beam counts")
      ->check(CLI::Range(1.0, 65000.0))
      ->capture_default_str();
  cmd->add_option("--coarse-size", o->coarse_size, "Voxels per axis of the planner's volume")
      ->check(CLI::Range(8, 1024))
      ->capture_default_str();
  cmd->add_option("--coarse-voxel", o->coarse_voxel_mm, "Voxel size of the planner's volume (mm)")
      ->check(positive_number)
      ->capture_default_str();
  cmd->add_option("--binning", o->binning, "Detector binning of the planner's reconstruction")
      ->check(CLI::Range(1, 64))
      ->capture_default_str();
  cmd->add_flag("--compare", o->compare,
                "Simulation mode: also acquire and reconstruct the whole-sphere and random trajectories of the same size");
  cmd->add_option("--random-draws", o->random_draws,
                  "With --compare: random trajectories to compare with (random/, random-2/ ...), summarised by mean and range")
      ->check(CLI::Range(1, 100))
      ->capture_default_str();
  cmd->add_option("--eval-size", o->eval_size,
                  "Voxels per axis of a cube for the comparison reconstructions (0: a volume holding the holder and the sample)")
      ->check(CLI::Range(0, 2048))
      ->capture_default_str();
  cmd->add_option("--eval-voxel", o->eval_voxel_mm, "Voxel size of the comparison reconstructions (mm)")
      ->check(positive_number)
      ->capture_default_str();
  cmd->add_option("--eval-iterations", o->eval_iterations, "WLS-CG iterations of the comparison reconstructions")
      ->check(CLI::Range(1, 1000))
      ->capture_default_str();
  cmd->add_option("--eval-lambda", o->eval_lambda, "Gradient penalty of the comparison reconstructions")
      ->check(non_negative_number)
      ->capture_default_str();
  cmd->add_flag("--compare-only", o->compare_only, "Reconstruct and compare the trajectories already in --out (no acquisition)");
  cmd->add_option("--eval-binning", o->eval_binning, "Detector binning of the comparison reconstructions")
      ->check(CLI::Range(1, 64))
      ->capture_default_str();
  cmd->callback([o] { run_plan(*o); });
}

}  // namespace ctk::tools

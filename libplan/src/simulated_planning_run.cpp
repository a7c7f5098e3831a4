#include "ctk/plan/simulated_planning_run.hpp"

#include <chrono>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include "ctk/core/atomic_write.hpp"
#include "ctk/core/error.hpp"
#include "ctk/core/provenance.hpp"
#include "ctk/core/volume_file.hpp"
#include "ctk/geom/holder_file.hpp"
#include "ctk/geom/run_files.hpp"
#include "ctk/geom/scan.hpp"
#include "ctk/geom/trajectory.hpp"
#include "ctk/measure/measurements.hpp"
#include "ctk/phantoms/builtin_phantoms.hpp"
#include "ctk/phantoms/render.hpp"
#include "ctk/plan/direction_list.hpp"
#include "ctk/plan/plan_pictures.hpp"
#include "ctk/plan/simulated_acquisition.hpp"

namespace ctk {

namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point start) { return std::chrono::duration<double>(Clock::now() - start).count(); }

// The folder of the k-th random trajectory (k from 0): random/, random-2/, random-3/ ...
std::string random_name(int k) { return k == 0 ? "random" : "random-" + std::to_string(k + 1); }

// The names the comparison gives its own trajectories, whatever the number of random draws (a
// folder of an earlier run with more draws must not be taken for a given trajectory).
bool is_comparison_name(const std::string& name) {
  if (name == "planned" || name == "whole-sphere") return true;
  for (int k = 0; k < SimulatedPlanRequest::kMostRandomDraws; ++k)
    if (name == random_name(k)) return true;
  return false;
}

std::vector<std::string> compared_names(int random_draws, const std::vector<DirectionList>& given) {
  std::vector<std::string> names = {"planned", "whole-sphere"};
  for (int k = 0; k < random_draws; ++k) names.push_back(random_name(k));
  for (const DirectionList& list : given) names.push_back(list.name);
  return names;
}

// The trajectories the request gives as direction lists, each name once.
std::vector<DirectionList> given_trajectories(const SimulatedPlanRequest& o) {
  std::vector<DirectionList> given;
  for (const fs::path& file : o.compare_directions) {
    DirectionList list = read_direction_list(file);
    if (is_comparison_name(list.name))
      throw InputError(file.string(), "name",
                       "'" + list.name + "' is a trajectory the comparison makes itself; choose another name");
    for (const DirectionList& earlier : given)
      if (earlier.name == list.name)
        throw InputError(file.string(), "name", "'" + list.name + "' names another given trajectory too; each needs its own");
    given.push_back(std::move(list));
  }
  return given;
}

// The whole-sphere, the random and the given trajectories with as many views as the planned one.
// Each gets a lab of its own, so its n-th shot draws the same robot and photon noise as the planned
// one's n-th shot, whatever the planned run asked before (the comparison does not drift with the
// planner).
void acquire_others(const SimulatedPlanRequest& o, const std::vector<DirectionList>& given, const ScanSimulation& simulation,
                    const PlanningSetup& setup, int n, const SimulatedPlanningHooks& hooks, std::vector<PlanningRun>& runs) {
  struct Other {
    std::string name;
    std::vector<Eigen::Vector3d> order;
  };
  std::vector<Other> others = {{"whole-sphere", whole_sphere_order(o.plan.candidate_nside)}};
  for (int k = 0; k < o.random_draws; ++k)
    others.push_back({random_name(k), random_directions(6 * n, o.plan.seed + 17 + static_cast<std::uint64_t>(k))});
  for (const DirectionList& list : given) others.push_back({list.name, list.directions});
  for (const Other& other : others) {
    const auto start = Clock::now();
    PlanningOptions p = o.plan.planning_options();
    p.views = n;
    p.fixed_directions = other.order;
    p.max_attempts = static_cast<int>(other.order.size());
    SimulatedLab lab(simulation);
    SimulatedAcquisition acquisition(lab, o.out / other.name);
    PlanningResult r = plan_trajectory(acquisition, setup, p, [&](const PlannedViewRecord& v) {
      if (hooks.view) hooks.view(other.name, n, v);
    });
    runs.push_back(write_planning_run(other.name, o.out / other.name, std::move(r), setup, false, seconds_since(start)));
  }
}

// The comparison's volume holds everything in the beam: the holder's tube (118 mm tall) and the
// sample. What sticks out of a reconstruction volume is smeared into it by the views that look
// along it, so a cube around the sample alone (80 mm) scored trajectories by how often they looked
// along the tube: on the walnut, random draws of 100 views ranged from 0.0043 to 0.0049 in RMSE,
// the difference all in the 10 mm at each end of the cube.
VolumeLayout evaluation_layout(const ComparisonOptions& o, const ScanSimulation& simulation) {
  const Eigen::Vector3d voxel = Eigen::Vector3d::Constant(o.voxel_mm);
  if (o.size > 0) return VolumeLayout::centred({o.size, o.size, o.size}, voxel);
  Eigen::Vector3d reach = Eigen::Vector3d::Zero();
  for (const Phantom& p : {helix_holder_phantom(simulation.holder), simulation.sample})
    for (const Primitive& primitive : p.primitives)
      for (const Eigen::Vector3d& corner : primitive.bounding_corners()) reach = reach.cwiseMax(corner.cwiseAbs());
  std::array<int, 3> size{};
  for (int a = 0; a < 3; ++a) size[static_cast<std::size_t>(a)] = 2 * static_cast<int>(std::ceil(reach[a] / o.voxel_mm + 0.5));
  return VolumeLayout::centred(size, voxel);
}

// Every trajectory gets the same reconstruction: WLS-CG on a binned detector, gradient penalty.
// Only its calibrated views go in (a projection whose view could not be calibrated is on disk
// with the others but has no matrix).
struct EvaluationReconstruction {
  Volume volume;
  int views = 0;
};

EvaluationReconstruction evaluation_reconstruction(const fs::path& folder, const VolumeLayout& layout,
                                                   const ComparisonOptions& o) {
  const ScanDescription scan = read_scan(folder / "scan.json");
  const Geometry geometry = read_geometry(folder / "geometry.json");
  const Measurements m = load_measurements(scan, geometry);
  IncrementalOptions io;
  io.binning = o.binning;
  io.first_update_iterations = o.iterations;
  io.lambda = o.lambda;
  IncrementalReconstruction recon(layout, scan.detector, io);
  const Detector& d = scan.detector;
  const std::size_t n = m.line_integrals.pixels_per_view();
  for (int v = 0; v < m.line_integrals.views; ++v) {
    Image p{d.cols, d.rows, std::vector<float>(m.line_integrals.view(v), m.line_integrals.view(v) + n)};
    Image w{d.cols, d.rows, std::vector<float>(m.weights.view(v), m.weights.view(v) + n)};
    recon.add_view(m.matrices[static_cast<std::size_t>(v)], p, w);
  }
  recon.update();
  write_volume(recon.volume(), folder / "volume.nrrd");
  return {recon.volume(), m.line_integrals.views};
}

// One random trajectory is a lottery (on sample 2, six draws of 100 views ranged from 0.00199 to
// 0.00223 in RMSE), so with several draws the planned one is also set against their spread: each
// figure's mean, least and greatest, and how many draws did better than the planned trajectory.
// `quality` holds the planned trajectory, the whole sphere, then the `draws` random draws.
nlohmann::json random_draw_summary(const std::vector<TrajectoryQuality>& quality, std::size_t draws) {
  nlohmann::json summary = {{"count", draws}};
  const TrajectoryQuality& planned = quality.front();
  auto figure = [&](const char* key, double TrajectoryQuality::*member, bool lower_is_better) {
    double sum = 0, least = 1e300, most = -1e300;
    int better = 0;
    for (std::size_t i = 2; i < 2 + draws; ++i) {
      const double v = quality[i].*member;
      sum += v;
      least = std::min(least, v);
      most = std::max(most, v);
      if (lower_is_better ? v < planned.*member : v > planned.*member) ++better;
    }
    summary[key] = {
        {"mean", sum / static_cast<double>(draws)}, {"min", least}, {"max", most}, {"draws_better_than_planned", better}};
  };
  figure("rmse_per_mm", &TrajectoryQuality::rmse_per_mm, true);
  figure("rmse_outside_absorbers_per_mm", &TrajectoryQuality::rmse_outside_absorbers_per_mm, true);
  figure("rmse_level_matched_per_mm", &TrajectoryQuality::rmse_level_matched_per_mm, true);
  figure("edge_gradient_per_mm2", &TrajectoryQuality::edge_gradient_per_mm2, false);
  figure("profile_gradient_per_mm2", &TrajectoryQuality::profile_gradient_per_mm2, false);
  return summary;
}

TrajectoryComparison compare(const SimulatedPlanRequest& o, const std::vector<DirectionList>& given,
                             const ScanSimulation& simulation, const SimulatedPlanningHooks& hooks) {
  const Phantom& sample = simulation.sample;
  TrajectoryComparison c;
  c.names = compared_names(o.random_draws, given);
  for (const std::string& name : c.names)
    if (!fs::exists(o.out / name / "scan.json"))
      throw InputError((o.out / name / "scan.json").string(), "",
                       "no " + name + " trajectory to compare (run with compare first)");
  const VolumeLayout layout = evaluation_layout(o.comparison, simulation);
  const Volume truth = voxelised(sample, layout);
  const std::vector<MaterialVolume> materials = voxelised_per_material(sample, layout);
  write_volume(truth, o.out / "truth.nrrd");
  const SampleRegion region;
  const std::array<int, 3> through = centre_of_mass_voxel(truth, region);
  // Absorbers in the truth by the planner's own rule: more than times_wall the holder's wall.
  const float absorber_above = static_cast<float>(SegmentationOptions{}.times_wall * material::pom);
  std::vector<Volume> volumes;
  std::vector<int> views;
  for (const std::string& name : c.names) {
    if (hooks.log) {
      std::ostringstream line;
      line << "reconstructing " << name << " (" << layout.size[0] << " x " << layout.size[1] << " x " << layout.size[2] << " at "
           << o.comparison.voxel_mm << " mm, " << o.comparison.iterations << " WLS-CG iterations)";
      hooks.log(line.str());
    }
    EvaluationReconstruction r = evaluation_reconstruction(o.out / name, layout, o.comparison);
    volumes.push_back(std::move(r.volume));
    views.push_back(r.views);
  }
  c.views = views.front();
  nlohmann::json table = nlohmann::json::object();
  std::vector<ComparedTrajectory> pictured;
  for (std::size_t i = 0; i < c.names.size(); ++i) {
    const TrajectoryQuality q = trajectory_quality(volumes[i], truth, region, through, absorber_above, materials);
    c.quality.push_back(q);
    nlohmann::json levels = nlohmann::json::object();
    for (const MaterialLevel& m : q.material_levels) levels[m.material.empty() ? "(no material)" : m.material] = m.level;
    table[c.names[i]] = {{"views", views[i]},
                         {"rmse_per_mm", q.rmse_per_mm},
                         {"rmse_outside_absorbers_per_mm", q.rmse_outside_absorbers_per_mm},
                         {"rmse_level_matched_per_mm", q.rmse_level_matched_per_mm},
                         {"material_levels", levels},
                         {"edge_gradient_per_mm2", q.edge_gradient_per_mm2},
                         {"profile_gradient_per_mm2", q.profile_gradient_per_mm2}};
    if (i < 3) pictured.push_back({c.names[i], &volumes[i], q});  // planned, whole sphere, the first random draw
  }
  c.picture = o.out / "comparison.png";
  write_trajectory_comparison_png(pictured, truth, c.picture);
  const TrajectoryQuality& planned = c.quality.front();
  c.report = {{"format", "ctk-plan-comparison/1"},
              {"provenance", provenance()},
              {"sample", sample.name},
              {"volume",
               {{"size", layout.size},
                {"voxel_mm", o.comparison.voxel_mm},
                {"iterations", o.comparison.iterations},
                {"lambda", o.comparison.lambda},
                {"binning", o.comparison.binning}}},
              {"profile_through_voxel", through},
              {"absorbers_above_per_mm", absorber_above},
              {"truth_edge_gradient_per_mm2", planned.truth_edge_gradient_per_mm2},
              {"truth_profile_gradient_per_mm2", planned.truth_profile_gradient_per_mm2},
              {"trajectories", table},
              {"random_draws", random_draw_summary(c.quality, static_cast<std::size_t>(o.random_draws))}};
  // The acquisition's settings are known only when this run acquired (not with compare_only).
  if (!o.compare_only) {
    c.report["spectrum"] = {{"kvp", o.kvp}, {"filter_al_mm", o.filter_al_mm}};
    c.report["flat_counts"] = o.flat_counts;
  }
  c.file = o.out / "comparison.json";
  write_text_atomically(c.file, c.report.dump(2) + "\n");
  return c;
}

}  // namespace

ScanSimulation simulated_world(const SimulatedPlanRequest& o) {
  ScanSimulation sim;
  const Detector detector{o.cols, o.rows, o.pitch_mm, o.pitch_mm};
  sim.setup = reference_panda_setup(detector, o.sdd_mm, o.sod_mm);
  sim.holder = holder_named(o.holder);
  sim.sample = sample_of(o.phantoms);
  sim.spectrum = tube_spectrum(o.kvp, o.filter_al_mm);
  sim.counts = {o.flat_counts, 100};
  sim.seed = o.plan.seed;
  return sim;
}

void ComparisonOptions::validate() const {
  require_option(size >= 0, "ComparisonOptions.size", "0 (everything in the beam) or voxels per axis", size);
  require_option(voxel_mm > 0, "ComparisonOptions.voxel_mm", "a size above 0", voxel_mm);
  require_option(iterations >= 1, "ComparisonOptions.iterations", "at least 1", iterations);
  require_option(lambda >= 0, "ComparisonOptions.lambda", "0 or more", lambda);
  require_option(binning >= 1, "ComparisonOptions.binning", "at least 1", binning);
}

void SimulatedPlanRequest::validate() const {
  plan.validate();
  comparison.validate();
  require_choice(!phantoms.empty(), "SimulatedPlanRequest.phantoms", "at least one phantom in the holder", "none");
  require_choice(!out.empty(), "SimulatedPlanRequest.out", "an output folder", "nothing");
  require_option(cols >= 16, "SimulatedPlanRequest.cols", "at least 16", cols);
  require_option(rows >= 16, "SimulatedPlanRequest.rows", "at least 16", rows);
  require_option(pitch_mm > 0, "SimulatedPlanRequest.pitch_mm", "a pitch above 0", pitch_mm);
  require_option(sod_mm > 0, "SimulatedPlanRequest.sod_mm", "a distance above 0", sod_mm);
  require_option(sdd_mm > sod_mm, "SimulatedPlanRequest.sdd_mm", "more than sod_mm (the detector beyond the sample)", sdd_mm);
  require_option(kvp >= 16 && kvp <= 150, "SimulatedPlanRequest.kvp", "16 to 150 kV", kvp);
  require_option(filter_al_mm >= 0, "SimulatedPlanRequest.filter_al_mm", "0 or more", filter_al_mm);
  require_option(flat_counts >= 1, "SimulatedPlanRequest.flat_counts", "at least 1", flat_counts);
  require_option(random_draws >= 1 && random_draws <= kMostRandomDraws, "SimulatedPlanRequest.random_draws",
                 ("1 to " + std::to_string(kMostRandomDraws)).c_str(), random_draws);
  require_choice(compare_directions.empty() || compare || compare_only, "SimulatedPlanRequest.compare_directions",
                 "direction lists only with compare or compare_only", "lists without a comparison");
}

std::string TrajectoryComparison::brief() const {
  return "trajectories compared on " + report.value("sample", std::string()) + " (" + std::to_string(views) + " views each)";
}

std::string SimulatedPlanningRun::brief() const {
  std::vector<std::string> lines;
  for (const PlanningRun& r : trajectories) lines.push_back(r.brief());
  if (comparison) lines.push_back(comparison->brief());
  std::string s;
  for (const std::string& line : lines) {
    if (!s.empty()) s += '\n';
    s += line;
  }
  return s;
}

nlohmann::json SimulatedPlanningRun::report() const {
  nlohmann::json j = {{"trajectories", nlohmann::json::object()}, {"seconds", seconds}};
  for (const PlanningRun& r : trajectories) j["trajectories"][r.name] = r.report();
  if (comparison) j["comparison"] = comparison->report;
  return j;
}

SimulatedPlanningRun run_simulated_planning(const SimulatedPlanRequest& request, const SimulatedPlanningHooks& hooks) {
  const auto start = Clock::now();
  request.validate();
  RunFiles files;
  for (const std::string& name : request.phantoms)
    if (fs::path(name).extension() == ".json") files.input("phantoms", name);
  if (fs::path(request.holder).extension() == ".json") files.input("holder", request.holder);
  for (const fs::path& file : request.compare_directions) files.input("compare_directions", file);
  files.output_folder("out", request.out);
  files.check();
  const std::vector<DirectionList> given = given_trajectories(request);
  SimulatedPlanningRun run;
  if (request.compare_only) {
    run.comparison = compare(request, given, simulated_world(request), hooks);
    run.seconds = seconds_since(start);
    return run;
  }
  SimulatedLab lab(simulated_world(request));
  const PlanningSetup setup = planning_setup(lab.simulation());
  const fs::path folder = request.out / "planned";
  SimulatedAcquisition acquisition(lab, folder);
  PlanningResult r = plan_trajectory(acquisition, setup, request.plan.planning_options(), [&](const PlannedViewRecord& v) {
    if (hooks.view) hooks.view("planned", request.plan.views, v);
  });
  run.trajectories.push_back(write_planning_run("planned", folder, std::move(r), setup, true, seconds_since(start)));
  if (request.compare) {
    if (run.trajectories.front().result.calibrated() == 0)
      throw std::runtime_error("no view of the planned trajectory could be calibrated: nothing to compare (" +
                               run.trajectories.front().brief() + ")");
    acquire_others(request, given, lab.simulation(), setup, run.trajectories.front().result.calibrated(), hooks,
                   run.trajectories);
    run.comparison = compare(request, given, lab.simulation(), hooks);
  }
  run.seconds = seconds_since(start);
  return run;
}

}  // namespace ctk

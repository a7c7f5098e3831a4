#include "ctk/phantoms/simulation_run.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include "ctk/core/error.hpp"
#include "ctk/core/output_set.hpp"
#include "ctk/geom/holder_file.hpp"
#include "ctk/geom/run_files.hpp"
#include "ctk/geom/trajectory.hpp"
#include "ctk/phantoms/builtin_phantoms.hpp"
#include "ctk/phantoms/robot_trajectory.hpp"

namespace ctk {

namespace {

constexpr double kDegree = M_PI / 180.0;

// A fixed-length list of numbers under `key`, named in the error when it is not one.
template <int N>
Eigen::Matrix<double, N, 1> numbers(const nlohmann::json& value, const std::string& key) {
  if (!value.is_array() || static_cast<int>(value.size()) != N)
    throw std::invalid_argument("effect " + key + ": expected " + std::to_string(N) + " numbers, got " + value.dump());
  Eigen::Matrix<double, N, 1> v;
  for (int i = 0; i < N; ++i) {
    if (!value[static_cast<std::size_t>(i)].is_number())
      throw std::invalid_argument("effect " + key + ": expected numbers, got " + value.dump());
    v[i] = value[static_cast<std::size_t>(i)].get<double>();
  }
  return v;
}

double number(const nlohmann::json& value, const std::string& key) {
  if (!value.is_number()) throw std::invalid_argument("effect " + key + ": expected a number, got " + value.dump());
  return value.get<double>();
}

}  // namespace

void SimulationRequest::validate() const {
  require_option(!phantoms.empty(), "SimulationRequest.phantoms", "at least one phantom", 0);
  if (trajectory != "circular" && trajectory != "spherical" && trajectory != "cap" && trajectory != "random")
    throw std::invalid_argument("SimulationRequest.trajectory: expected circular, spherical, cap or random, got " + trajectory);
  require_option(views >= 1, "SimulationRequest.views", "1 or more", views);
  require_option(nside >= 1 && nside <= 64, "SimulationRequest.nside", "an integer in [1, 64]", nside);
  require_option(cap_min_deg >= 0 && cap_min_deg <= cap_max_deg && cap_max_deg <= 180, "SimulationRequest.cap_min_deg",
                 "0 <= cap_min_deg <= cap_max_deg <= 180", cap_min_deg);
  require_option(cols >= 1 && rows >= 1, "SimulationRequest.cols", "a detector of at least 1 x 1 pixels", cols);
  require_option(pitch_mm > 0 && sdd_mm > 0 && sod_mm > 0 && sod_mm < sdd_mm, "SimulationRequest.sod_mm",
                 "positive pitch and distances, the isocentre between source and detector", sod_mm);
  require_option(supersampling >= 1 && supersampling <= 16, "SimulationRequest.supersampling", "an integer in [1, 16]",
                 supersampling);
  require_option(counts.flat_counts >= 1 && counts.flat_counts <= 65000, "SimulationRequest.counts.flat_counts",
                 "counts in [1, 65000]", counts.flat_counts);
  require_option(counts.dark_counts >= 0 && counts.dark_counts <= 10000, "SimulationRequest.counts.dark_counts",
                 "counts in [0, 10000]", counts.dark_counts);
  if (kvp) require_option(*kvp >= 16 && *kvp <= 150, "SimulationRequest.kvp", "a tube voltage in [16, 150] kV", *kvp);
  require_option(filter_al_mm >= 0, "SimulationRequest.filter_al_mm", "a thickness of 0 or more", filter_al_mm);
  require_option(robot_noise.translation_mm >= 0 && robot_noise.rotation_deg >= 0, "SimulationRequest.robot_noise",
                 "RMS values of 0 or more", robot_noise.translation_mm);
}

std::string SimulationRun::brief() const {
  std::ostringstream s;
  s << "simulated scan written to " << scan_file.string() << ": " << report.views << " views (" << report.views_acquired
    << " acquired, " << report.views - report.views_acquired << " unreachable), " << cols << " x " << rows
    << " px, phantom: " << in_the_beam;
  return s.str();
}

SimulationEffects simulation_effects_from_json(const nlohmann::json& named, const Detector& detector) {
  if (!named.is_object()) throw std::invalid_argument("effects: expected names with values, got " + named.dump());
  SimulationEffects e;
  auto has = [&](const char* key) { return named.contains(key); };
  auto vec3 = [&](const char* key) { return has(key) ? Eigen::Vector3d(numbers<3>(named[key], key)) : Eigen::Vector3d::Zero(); };
  auto vec2 = [&](const char* key) { return has(key) ? Eigen::Vector2d(numbers<2>(named[key], key)) : Eigen::Vector2d::Zero(); };
  static const char* const kKnown[] = {"sdd_error_mm",         "principal_point_error_px",
                                       "detector_tilt_deg",    "distortion_k1",
                                       "distortion_centre_px", "displaced_spheres",
                                       "displacement_mm",      "base_translation_mm",
                                       "base_rotation_deg",    "mount_translation_mm",
                                       "mount_rotation_deg",   "joint_offsets_deg",
                                       "source_drift_mm",      "holder_sag_deg",
                                       "source_wobble_mm",     "moving_sphere_mm",
                                       "blur_fraction",        "blur_sigma_px",
                                       "false_blobs",          "scatter_fraction",
                                       "detector_psf_px",      "focal_spot_mm",
                                       "detector_lag",         "robot_clusters_mm",
                                       "robot_droop_mm_per_m", "sphere_jitter_mm",
                                       "holder_seed"};
  for (const auto& item : named.items()) {
    const std::string& key = item.key();
    if (std::find_if(std::begin(kKnown), std::end(kKnown), [&](const char* k) { return key == k; }) == std::end(kKnown))
      throw std::invalid_argument("effect " + key + ": not an effect the simulator knows");
  }
  if (has("sdd_error_mm") || has("principal_point_error_px") || has("detector_tilt_deg"))
    e.detector_intrinsics = DetectorIntrinsicsError{has("sdd_error_mm") ? number(named["sdd_error_mm"], "sdd_error_mm") : 0.0,
                                                    vec2("principal_point_error_px"), vec2("detector_tilt_deg")};
  if (has("distortion_k1"))
    e.detector_distortion = RadialDistortion{number(named["distortion_k1"], "distortion_k1"),
                                             has("distortion_centre_px") ? vec2("distortion_centre_px") : detector.centre_px()};
  if (has("displaced_spheres"))
    e.sphere_positions = SphereDisplacement{static_cast<int>(number(named["displaced_spheres"], "displaced_spheres")),
                                            has("displacement_mm") ? number(named["displacement_mm"], "displacement_mm") : 0.2};
  if (has("sphere_jitter_mm")) {
    const double sigma = number(named["sphere_jitter_mm"], "sphere_jitter_mm");
    if (!(sigma > 0 && sigma <= 10)) throw std::invalid_argument("sphere_jitter_mm: expected a sigma in (0, 10] mm");
    const double seed = has("holder_seed") ? number(named["holder_seed"], "holder_seed") : 1.0;
    if (!(seed >= 0 && seed < 9e15 && seed == std::floor(seed)))
      throw std::invalid_argument("holder_seed: expected a whole number of 0 or more");
    e.printed_holder = PrintedHolder{sigma, static_cast<std::uint64_t>(seed)};
  } else if (has("holder_seed")) {
    throw std::invalid_argument("holder_seed: only with sphere_jitter_mm (the printed holder it draws)");
  }
  if (has("base_translation_mm") || has("base_rotation_deg"))
    e.robot_base_frame = RigidOffset{vec3("base_translation_mm"), vec3("base_rotation_deg")};
  if (has("mount_translation_mm") || has("mount_rotation_deg"))
    e.holder_mount = RigidOffset{vec3("mount_translation_mm"), vec3("mount_rotation_deg")};
  if (has("joint_offsets_deg")) {
    const auto q_deg = numbers<7>(named["joint_offsets_deg"], "joint_offsets_deg");
    panda::Joints q{};
    for (std::size_t j = 0; j < q.size(); ++j) q[j] = q_deg[static_cast<int>(j)] * kDegree;
    e.joint_offsets_rad = q;
  }
  if (has("source_drift_mm")) e.source_drift_mm_per_100_views = vec2("source_drift_mm");
  if (has("holder_sag_deg")) e.holder_sag_deg = number(named["holder_sag_deg"], "holder_sag_deg");
  if (has("source_wobble_mm")) e.source_wobble_mm = vec2("source_wobble_mm");
  if (has("moving_sphere_mm")) e.moving_sphere_mm = number(named["moving_sphere_mm"], "moving_sphere_mm");
  if (has("blur_fraction"))
    e.blurred_views = BlurredViews{number(named["blur_fraction"], "blur_fraction"),
                                   has("blur_sigma_px") ? number(named["blur_sigma_px"], "blur_sigma_px") : 2.0};
  if (has("false_blobs")) e.false_blobs_per_view = static_cast<int>(number(named["false_blobs"], "false_blobs"));
  const std::pair<const char*, std::optional<double>*> nuisances[] = {
      {"scatter_fraction", &e.scatter_fraction},   {"detector_psf_px", &e.detector_psf_px},
      {"focal_spot_mm", &e.focal_spot_mm},         {"detector_lag", &e.detector_lag},
      {"robot_clusters_mm", &e.robot_clusters_mm}, {"robot_droop_mm_per_m", &e.robot_droop_mm_per_m}};
  for (const auto& [key, field] : nuisances)
    if (has(key)) {
      const double value = number(named[key], key);
      if (!(value >= 0) || (std::string(key) == "detector_lag" && !(value < 1)))
        throw std::invalid_argument(std::string(key) + ": expected a value of 0 or more" +
                                    (std::string(key) == "detector_lag" ? " and below 1" : "") + ", got " +
                                    std::to_string(value));
      *field = value;
    }
  return e;
}

SimulationRun run_simulation(const SimulationRequest& r, const std::filesystem::path& out,
                             const std::function<void(int, int)>& progress, const std::function<void(const std::string&)>& log) {
  namespace fs = std::filesystem;
  const auto start = std::chrono::steady_clock::now();
  r.validate();
  if (out.empty()) throw std::invalid_argument("out: expected the scan folder to write, got an empty name");
  const auto say = [&](const std::string& line) {
    if (log) log(line);
  };
  // Running again into a simulation's folder replaces it; a scan that no simulation wrote (a
  // measured one: scan.json without truth.json) is never overwritten by a slip of the folder.
  if (fs::exists(out / "scan.json") && !fs::exists(out / "truth.json"))
    throw InputError(out.string(), "",
                     "holds a scan that ctk simulate did not write (scan.json without truth.json): choose another folder");
  RunFiles files;
  for (const std::string& name : r.phantoms)
    if (fs::path(name).extension() == ".json") files.input("phantom", name);
  files.input("poses", r.poses);
  if (fs::path(r.holder).extension() == ".json") files.input("holder", r.holder);
  const std::vector<std::string> written = {"scan.json", "truth.json", "truth-geometry.json", "joints.csv", "poses.json",
                                            "flat.tif",  "dark.tif",   "projections"};
  for (const std::string& name : written)
    if (name != "projections") files.output("the scan folder's " + name, out / name);
  files.output_folder("the scan folder's projections", out / "projections");
  files.check();

  const Detector detector{r.cols, r.rows, r.pitch_mm, r.pitch_mm};
  ScanSimulation sim;
  sim.setup = reference_panda_setup(detector, r.sdd_mm, r.sod_mm);
  sim.holder = holder_named(r.holder);
  sim.with_holder = false;
  std::vector<std::string> sample;  // the holder is drawn apart, from the scan's own description
  for (const std::string& name : r.phantoms) {
    if (name == "helix-holder")
      sim.with_holder = true;
    else
      sample.push_back(name);
  }
  std::vector<std::string> warnings;
  sim.sample = sample_of(sample, &warnings);
  for (const auto& w : warnings) say("warning: " + w);
  if (!r.poses.empty()) {
    sim.poses = read_geometry(r.poses);
    if (sim.poses->detector.cols != r.cols || sim.poses->detector.rows != r.rows)
      throw InputError(r.poses.string(), json_key("detector"), "is not the simulated detector (cols, rows)");
  } else if (r.trajectory == "circular") {
    sim.trajectory = circular_robot_trajectory(sim.setup, r.views);
  } else {
    std::vector<Eigen::Vector3d> directions;
    if (r.trajectory == "spherical")
      directions = HealpixSphere(r.nside).directions();
    else if (r.trajectory == "cap")
      directions = spinning_cap_directions(r.views, r.cap_min_deg * kDegree, r.cap_max_deg * kDegree);
    else
      directions = random_directions(r.views, r.seed);
    say("planning " + std::to_string(directions.size()) + " " + r.trajectory + " views (numerical IK) ...");
    sim.trajectory = spherical_robot_trajectory(sim.setup, directions);
  }
  sim.supersampling = r.supersampling;
  if (r.kvp) sim.spectrum = tube_spectrum(*r.kvp, r.filter_al_mm);
  sim.output = r.output;
  sim.counts = r.counts;
  sim.robot_noise = r.robot_noise;
  sim.effects = r.effects;
  sim.seed = r.seed;

  // The scan is written whole into a hidden folder beside `out` and swapped in at the end: an
  // interrupted run leaves the earlier scan as it was, never new projections under an old truth.
  StagedFolder folder(out, written);
  SimulationRun run;
  run.report = simulate_scan(sim, folder.path(), progress);
  folder.commit();
  run.scan_file = out / "scan.json";
  run.in_the_beam = std::string(sim.with_holder ? "helix-holder " : "") + sim.sample.name;
  run.cols = r.cols;
  run.rows = r.rows;
  run.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return run;
}

}  // namespace ctk

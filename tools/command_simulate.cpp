// ctk simulate: a scan folder from analytic phantoms — exact line integrals, robot poses from a
// joint log through Panda FK (circular or spherical trajectory, or given matrices), detector
// noise, and any undeclared effects, with the truth beside it (truth.json).
#include <chrono>
#include <filesystem>
#include <iostream>

#include "commands.hpp"
#include "ctk/geom/output_set.hpp"
#include "ctk/geom/run_files.hpp"
#include "option_checks.hpp"
#include "ctk/geom/error.hpp"
#include "ctk/geom/trajectory.hpp"
#include "ctk/phantoms/builtin_phantoms.hpp"
#include "ctk/phantoms/scan_simulation.hpp"
#include "progress.hpp"

namespace ctk::tools {

namespace {

constexpr double kDegree = M_PI / 180.0;

struct SimulateOptions {
  std::filesystem::path out = "simulated-scan";
  std::vector<std::string> phantoms{"helix-holder"};
  std::string trajectory = "circular";
  int views = 360, nside = 3;
  std::vector<double> cap_deg{5.0, 90.0};
  std::filesystem::path poses;
  int cols = 720, rows = 720;
  double pitch_mm = 0.6, sdd_mm = 2150.0, sod_mm = 1360.0;
  int supersampling = 2;
  std::string output = "counts";
  double flat_counts = 1e4, dark_counts = 100;
  std::optional<double> kvp;
  double filter_al_mm = 2.0;
  double robot_noise_mm = 0.1, robot_noise_deg = 0.02;
  std::uint64_t seed = 1;
  // Effects (unset: off).
  std::optional<double> sdd_error_mm;
  std::vector<double> principal_point_error_px, tilt_deg, distortion_centre_px;
  std::optional<double> distortion_k1;
  std::optional<int> displaced_spheres;
  double displacement_mm = 0.2;
  std::vector<double> base_translation_mm, base_rotation_deg, mount_translation_mm, mount_rotation_deg, joint_offsets_deg,
      source_drift_mm;
  std::optional<double> holder_sag_deg;
  std::vector<double> source_wobble_mm;
  std::optional<double> moving_sphere_mm;
  std::optional<double> blur_fraction;
  double blur_sigma_px = 2.0;
  std::optional<int> false_blobs;
};

Eigen::Vector3d vec3(const std::vector<double>& v) {
  return v.empty() ? Eigen::Vector3d::Zero() : Eigen::Vector3d(v[0], v[1], v[2]);
}
Eigen::Vector2d vec2(const std::vector<double>& v) { return v.empty() ? Eigen::Vector2d::Zero() : Eigen::Vector2d(v[0], v[1]); }

SimulationEffects effects_from(const SimulateOptions& o, const PandaSetup& setup) {
  SimulationEffects e;
  if (o.sdd_error_mm || !o.principal_point_error_px.empty() || !o.tilt_deg.empty())
    e.detector_intrinsics =
        DetectorIntrinsicsError{o.sdd_error_mm.value_or(0.0), vec2(o.principal_point_error_px), vec2(o.tilt_deg)};
  if (o.distortion_k1)
    e.detector_distortion = RadialDistortion{
        *o.distortion_k1, o.distortion_centre_px.empty() ? setup.detector.centre_px() : vec2(o.distortion_centre_px)};
  if (o.displaced_spheres) e.sphere_positions = SphereDisplacement{*o.displaced_spheres, o.displacement_mm};
  if (!o.base_translation_mm.empty() || !o.base_rotation_deg.empty())
    e.robot_base_frame = RigidOffset{vec3(o.base_translation_mm), vec3(o.base_rotation_deg)};
  if (!o.mount_translation_mm.empty() || !o.mount_rotation_deg.empty())
    e.holder_mount = RigidOffset{vec3(o.mount_translation_mm), vec3(o.mount_rotation_deg)};
  if (!o.joint_offsets_deg.empty()) {
    panda::Joints q{};
    for (std::size_t j = 0; j < q.size(); ++j) q[j] = o.joint_offsets_deg[j] * kDegree;
    e.joint_offsets_rad = q;
  }
  if (!o.source_drift_mm.empty()) e.source_drift_mm_per_100_views = vec2(o.source_drift_mm);
  if (o.holder_sag_deg) e.holder_sag_deg = *o.holder_sag_deg;
  if (!o.source_wobble_mm.empty()) e.source_wobble_mm = vec2(o.source_wobble_mm);
  if (o.moving_sphere_mm) e.moving_sphere_mm = *o.moving_sphere_mm;
  if (o.blur_fraction) e.blurred_views = BlurredViews{*o.blur_fraction, o.blur_sigma_px};
  if (o.false_blobs) e.false_blobs_per_view = *o.false_blobs;
  return e;
}

void run_simulate(const SimulateOptions& o) {
  const auto start = std::chrono::steady_clock::now();
  // Running again into a simulation's folder replaces it; a scan that no simulation wrote (a
  // measured one: scan.json without truth.json) is never overwritten by a slip of --out.
  if (std::filesystem::exists(o.out / "scan.json") && !std::filesystem::exists(o.out / "truth.json"))
    throw InputError(
        "--out", "",
        o.out.string() + " holds a scan that ctk simulate did not write (scan.json without truth.json): choose another folder");
  RunFiles files;
  for (const std::string& name : o.phantoms)
    if (std::filesystem::path(name).extension() == ".json") files.input("--phantom", name);
  files.input("--poses", o.poses);
  const std::vector<std::string> written = {"scan.json", "truth.json", "truth-geometry.json", "joints.csv", "poses.json",
                                            "flat.tif",  "dark.tif",   "projections"};
  for (const std::string& name : written)
    if (name != "projections") files.output("--out: " + name, o.out / name);
  files.output_folder("--out: projections", o.out / "projections");
  files.check();
  // The scan is written whole into a hidden folder beside --out and swapped in at the end: an
  // interrupted run leaves the earlier scan as it was, never new projections under an old truth.
  StagedFolder folder(o.out, written);
  const Detector detector{o.cols, o.rows, o.pitch_mm, o.pitch_mm};
  ScanSimulation sim;
  sim.setup = reference_panda_setup(detector, o.sdd_mm, o.sod_mm);
  sim.holder = reference_helix_holder();
  sim.with_holder = false;
  for (const std::string& name : o.phantoms) {
    if (name == "helix-holder") {
      sim.with_holder = true;
      continue;
    }
    const bool is_file = std::filesystem::path(name).extension() == ".json";
    std::vector<std::string> warnings;
    const Phantom p = is_file ? read_phantom(name, &warnings) : builtin_phantom(name);
    for (const auto& w : warnings) std::cerr << "warning: " << w << "\n";
    sim.sample.name += (sim.sample.name.empty() ? "" : " + ") + p.name;
    sim.sample.add(p);
  }
  if (!o.poses.empty()) {
    sim.poses = read_geometry(o.poses);
    if (sim.poses->detector.cols != o.cols || sim.poses->detector.rows != o.rows)
      throw InputError(o.poses.string(), json_key("detector"), "is not the simulated detector (--cols, --rows)");
  } else if (o.trajectory == "circular") {
    sim.trajectory = circular_robot_trajectory(sim.setup, o.views);
  } else {
    std::vector<Eigen::Vector3d> directions;
    if (o.trajectory == "spherical")
      directions = HealpixSphere(o.nside).directions();
    else if (o.trajectory == "cap" && o.cap_deg[0] > o.cap_deg[1])
      throw InputError(
          "--cap-deg", "",
          "expected the least angle first, got " + std::to_string(o.cap_deg[0]) + " before " + std::to_string(o.cap_deg[1]));
    else if (o.trajectory == "cap")
      directions = spinning_cap_directions(o.views, o.cap_deg[0] * kDegree, o.cap_deg[1] * kDegree);
    else
      directions = random_directions(o.views, o.seed);
    std::cerr << "planning " << directions.size() << " " << o.trajectory << " views (numerical IK) ...\n";
    sim.trajectory = spherical_robot_trajectory(sim.setup, directions);
  }
  sim.supersampling = o.supersampling;
  if (o.kvp) sim.spectrum = tube_spectrum(*o.kvp, o.filter_al_mm);
  sim.output = o.output == "counts" ? SimulatedOutput::counts : SimulatedOutput::line_integrals;
  sim.counts = {o.flat_counts, o.dark_counts};
  sim.robot_noise = {o.robot_noise_mm, o.robot_noise_deg};
  sim.effects = effects_from(o, sim.setup);
  sim.seed = o.seed;

  Progress progress("simulate", "views");
  const SimulationReport r = simulate_scan(sim, folder.path(), std::ref(progress));
  folder.commit();
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::cout << "simulated scan written to " << (o.out / "scan.json").string() << ": " << r.views << " views (" << r.views_acquired
            << " acquired, " << r.views - r.views_acquired << " unreachable), " << o.cols << " x " << o.rows
            << " px, phantom: " << (sim.with_holder ? "helix-holder " : "") << sim.sample.name << "\n";
  if (r.saturated_pixels > 0) std::cout << "warning: " << r.saturated_pixels << " pixels saturated at 65535 counts\n";
  std::cout << "truth (true matrices, poses, effects applied) in " << (o.out / "truth.json").string() << "; " << seconds
            << " s\n";
}

}  // namespace

void register_simulate(CLI::App& app) {
  auto o = std::make_shared<SimulateOptions>();
  CLI::App* cmd = app.add_subcommand("simulate", "Simulate a scan of analytic phantoms, with its truth (truth.json)");
  cmd->add_option("--out", o->out, "Scan folder to write")->capture_default_str();
  cmd->add_option("--phantom", o->phantoms,
                  "Phantoms in the beam: built-in names (helix-holder, shepp-logan, brick-and-plate, sample-1, sample-2, "
                  "walnut) or ctk-phantom/1 files (.json); repeat to combine")
      ->capture_default_str();
  auto* poses = cmd->add_option("--poses", o->poses, "Per-view matrices (ctk-geometry/1) instead of a robot trajectory")
                    ->check(CLI::ExistingFile);
  cmd->add_option("--trajectory", o->trajectory,
                  "Robot trajectory: circular (joint 7 orbit), spherical (HEALPix directions), cap (--cap-deg band of directions "
                  "about the holder axis while it spins), random (uniform directions from --seed)")
      ->check(CLI::IsMember({"circular", "spherical", "cap", "random"}))
      ->capture_default_str()
      ->excludes(poses);
  cmd->add_option("--views", o->views, "Views of a circular, cap or random trajectory")
      ->check(CLI::Range(1, 100000))
      ->capture_default_str();
  cmd->add_option("--cap-deg", o->cap_deg, "A cap trajectory's band: least and greatest angle between beam and holder axis")
      ->expected(2)
      ->check(CLI::Range(0.0, 180.0))
      ->capture_default_str();
  cmd->add_option("--nside", o->nside, "HEALPix resolution of a spherical trajectory (12 nside^2 directions)")
      ->check(CLI::Range(1, 64))
      ->capture_default_str();
  cmd->add_option("--cols", o->cols, "Detector columns")->check(CLI::Range(1, 100000))->capture_default_str();
  cmd->add_option("--rows", o->rows, "Detector rows")->check(CLI::Range(1, 100000))->capture_default_str();
  cmd->add_option("--pitch", o->pitch_mm, "Pixel pitch (mm)")->check(positive_number)->capture_default_str();
  cmd->add_option("--sdd", o->sdd_mm, "Source-to-detector distance (mm)")->check(positive_number)->capture_default_str();
  cmd->add_option("--sod", o->sod_mm, "Source-to-isocentre distance (mm)")->check(positive_number)->capture_default_str();
  cmd->add_option("--supersampling", o->supersampling, "s x s rays per pixel")->check(CLI::Range(1, 16))->capture_default_str();
  cmd->add_option("--output", o->output, "counts: 16-bit TIFF with flat and dark; line-integrals: float EXR, noise-free")
      ->check(CLI::IsMember({"counts", "line-integrals"}))
      ->capture_default_str();
  cmd->add_option("--flat-counts", o->flat_counts, "Mean counts above dark, open beam")
      ->check(CLI::Range(1.0, 65000.0))
      ->capture_default_str();
  cmd->add_option("--dark-counts", o->dark_counts, "Dark offset (counts)")
      ->check(CLI::Range(0.0, 10000.0))
      ->capture_default_str();
  cmd->add_option("--kvp", o->kvp, "Polychromatic rays from a tube at this voltage (Kramers spectrum; beam hardening)")
      ->check(CLI::Range(16.0, 150.0));
  cmd->add_option("--filter-al-mm", o->filter_al_mm, "Aluminium filter of the polychromatic spectrum")
      ->check(non_negative_number)
      ->capture_default_str();
  cmd->add_option("--robot-noise-mm", o->robot_noise_mm, "Pose repeatability, RMS translation (0: off)")
      ->check(non_negative_number)
      ->capture_default_str();
  cmd->add_option("--robot-noise-deg", o->robot_noise_deg, "Pose repeatability, RMS rotation (0: off)")
      ->check(non_negative_number)
      ->capture_default_str();
  cmd->add_option("--seed", o->seed, "Random seed (noise, effects)")->capture_default_str();

  const std::string effects = "Effects (undeclared: only truth.json knows)";
  cmd->add_option("--sdd-error-mm", o->sdd_error_mm, "True SDD minus declared")->group(effects);
  cmd->add_option("--principal-point-error-px", o->principal_point_error_px, "True (u0, v0) minus declared")
      ->expected(2)
      ->group(effects);
  cmd->add_option("--detector-tilt-deg", o->tilt_deg, "Out-of-plane tilt about u, then v")->expected(2)->group(effects);
  cmd->add_option("--distortion-k1", o->distortion_k1, "Radial distortion k1 (1/px^2)")->group(effects);
  cmd->add_option("--distortion-centre-px", o->distortion_centre_px, "Distortion centre (default: detector centre)")
      ->expected(2)
      ->group(effects);
  cmd->add_option("--displaced-spheres", o->displaced_spheres, "Number of spheres off their declared centre")
      ->check(CLI::Range(0, 1000))
      ->group(effects);
  cmd->add_option("--displacement-mm", o->displacement_mm, "How far each displaced sphere is off")
      ->check(positive_number)
      ->capture_default_str()
      ->group(effects);
  cmd->add_option("--base-translation-mm", o->base_translation_mm, "Robot base-frame offset (base axes)")
      ->expected(3)
      ->group(effects);
  cmd->add_option("--base-rotation-deg", o->base_rotation_deg, "Robot base-frame rotation vector")->expected(3)->group(effects);
  cmd->add_option("--mount-translation-mm", o->mount_translation_mm, "Holder-mount offset (flange axes)")
      ->expected(3)
      ->group(effects);
  cmd->add_option("--mount-rotation-deg", o->mount_rotation_deg, "Holder-mount rotation vector")->expected(3)->group(effects);
  cmd->add_option("--joint-offsets-deg", o->joint_offsets_deg, "Encoder zero offsets q1..q7 (true = logged + offset)")
      ->expected(7)
      ->group(effects);
  cmd->add_option("--source-drift-mm", o->source_drift_mm, "Focal-spot drift per 100 views (camera x, y)")
      ->expected(2)
      ->group(effects);
  cmd->add_option("--holder-sag-deg", o->holder_sag_deg,
                  "Outside the diagnosis' vocabulary: the holder turns towards gravity by this much times the sine of its axis' "
                  "angle to it")
      ->group(effects);
  cmd->add_option("--source-wobble-mm", o->source_wobble_mm,
                  "Outside the vocabulary: the focal spot wanders by this amplitude * cos(4 pi view / views) (camera x, y)")
      ->expected(2)
      ->group(effects);
  cmd->add_option("--moving-sphere-mm", o->moving_sphere_mm,
                  "Outside the vocabulary: one sphere moves this far (random direction) from the first view to the last")
      ->check(positive_number)
      ->group(effects);
  cmd->add_option("--blur-fraction", o->blur_fraction, "Fraction of views blurred")->check(CLI::Range(0.0, 1.0))->group(effects);
  cmd->add_option("--blur-sigma-px", o->blur_sigma_px, "Blur of those views")
      ->check(positive_number)
      ->capture_default_str()
      ->group(effects);
  cmd->add_option("--false-blobs", o->false_blobs, "Spurious sphere-like blobs per view")
      ->check(CLI::Range(0, 10000))
      ->group(effects);
  cmd->callback([o] { run_simulate(*o); });
}

}  // namespace ctk::tools

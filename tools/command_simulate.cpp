// ctk simulate: a scan folder from analytic phantoms (phantoms' run_simulation) — exact line
// integrals, robot poses from a joint log through Panda FK (circular or spherical trajectory, or
// given matrices), detector noise, and any undeclared effects, with the truth beside it.
#include <filesystem>
#include <iostream>

#include "commands.hpp"
#include "ctk/core/error.hpp"
#include "ctk/phantoms/simulation_run.hpp"
#include "interruption.hpp"
#include "option_checks.hpp"
#include "progress.hpp"

namespace ctk::tools {

namespace {

struct SimulateOptions {
  std::filesystem::path out = "simulated-scan";
  SimulationRequest request;  // the options bound straight into the library's fields and defaults
  std::vector<double> cap_deg{request.cap_min_deg, request.cap_max_deg};
  std::string output = "counts";
  // Effects (unset: off).
  std::optional<double> sdd_error_mm;
  std::vector<double> principal_point_error_px, tilt_deg, distortion_centre_px;
  std::optional<double> distortion_k1;
  std::optional<int> displaced_spheres;
  double displacement_mm = 0.2;
  std::optional<double> sphere_jitter_mm;
  std::uint64_t holder_seed = 1;
  std::vector<double> base_translation_mm, base_rotation_deg, mount_translation_mm, mount_rotation_deg, joint_offsets_deg,
      source_drift_mm;
  std::optional<double> holder_sag_deg;
  std::vector<double> source_wobble_mm;
  std::optional<double> moving_sphere_mm;
  std::optional<double> blur_fraction;
  double blur_sigma_px = 2.0;
  std::optional<int> false_blobs;
  std::optional<double> scatter_fraction, detector_psf_px, focal_spot_mm, detector_lag, robot_clusters_mm, robot_droop_mm_per_m;
};

// The effect options by the names the library's request takes (simulation_run.hpp).
nlohmann::json named_effects(const SimulateOptions& o) {
  nlohmann::json e = nlohmann::json::object();
  auto put = [&](const char* key, const auto& value) { e[key] = value; };
  auto put_list = [&](const char* key, const std::vector<double>& v) {
    if (!v.empty()) e[key] = v;
  };
  if (o.sdd_error_mm) put("sdd_error_mm", *o.sdd_error_mm);
  put_list("principal_point_error_px", o.principal_point_error_px);
  put_list("detector_tilt_deg", o.tilt_deg);
  if (o.distortion_k1) put("distortion_k1", *o.distortion_k1);
  put_list("distortion_centre_px", o.distortion_centre_px);
  if (o.displaced_spheres) {
    put("displaced_spheres", *o.displaced_spheres);
    put("displacement_mm", o.displacement_mm);
  }
  if (o.sphere_jitter_mm) {
    put("sphere_jitter_mm", *o.sphere_jitter_mm);
    put("holder_seed", o.holder_seed);
  }
  put_list("base_translation_mm", o.base_translation_mm);
  put_list("base_rotation_deg", o.base_rotation_deg);
  put_list("mount_translation_mm", o.mount_translation_mm);
  put_list("mount_rotation_deg", o.mount_rotation_deg);
  put_list("joint_offsets_deg", o.joint_offsets_deg);
  put_list("source_drift_mm", o.source_drift_mm);
  if (o.holder_sag_deg) put("holder_sag_deg", *o.holder_sag_deg);
  put_list("source_wobble_mm", o.source_wobble_mm);
  if (o.moving_sphere_mm) put("moving_sphere_mm", *o.moving_sphere_mm);
  if (o.blur_fraction) {
    put("blur_fraction", *o.blur_fraction);
    put("blur_sigma_px", o.blur_sigma_px);
  }
  if (o.false_blobs) put("false_blobs", *o.false_blobs);
  for (const auto& [key, value] :
       {std::pair{"scatter_fraction", o.scatter_fraction}, std::pair{"detector_psf_px", o.detector_psf_px},
        std::pair{"focal_spot_mm", o.focal_spot_mm}, std::pair{"detector_lag", o.detector_lag},
        std::pair{"robot_clusters_mm", o.robot_clusters_mm}, std::pair{"robot_droop_mm_per_m", o.robot_droop_mm_per_m}})
    if (value) put(key, *value);
  return e;
}

void run_simulate(const SimulateOptions& o) {
  if (o.request.trajectory == "cap" && o.cap_deg[0] > o.cap_deg[1])
    throw InputError(
        "--cap-deg", "",
        "expected the least angle first, got " + std::to_string(o.cap_deg[0]) + " before " + std::to_string(o.cap_deg[1]));
  SimulationRequest r = o.request;
  r.cap_min_deg = o.cap_deg[0];
  r.cap_max_deg = o.cap_deg[1];
  r.output = o.output == "counts" ? SimulatedOutput::counts : SimulatedOutput::line_integrals;
  r.effects = simulation_effects_from_json(named_effects(o), Detector{r.cols, r.rows, r.pitch_mm, r.pitch_mm});
  Progress progress("simulate", "views");
  // Ctrl-C stops the views being drawn; the scan, written into a hidden folder, is not published.
  const InterruptionWatch watch(InterruptionWatch::Stop::the_parallel_loops_too);
  SimulationRun run;
  try {
    run = run_simulation(r, o.out, std::ref(progress), [](const std::string& line) { std::cerr << line << "\n"; });
  } catch (const Cancelled&) {
    throw Interrupted("simulate stopped by Ctrl-C: nothing written, " + o.out.string() + " as it was");
  }
  std::cout << run.brief() << "\n";
  if (run.report.saturated_pixels > 0)
    std::cout << "warning: " << run.report.saturated_pixels << " pixels saturated at 65535 counts\n";
  std::cout << "truth (true matrices, poses, effects applied) in " << (o.out / "truth.json").string() << "; " << run.seconds
            << " s\n";
}

}  // namespace

// NOLINTNEXTLINE(readability-function-size): one statement per option, in the order --help lists them
void register_simulate(CLI::App& app) {
  auto o = std::make_shared<SimulateOptions>();
  CLI::App* cmd = app.add_subcommand("simulate", "Simulate a scan of analytic phantoms, with its truth (truth.json)");
  cmd->add_option("--out", o->out, "Scan folder to write")->capture_default_str();
  cmd->add_option("--phantom", o->request.phantoms,
                  "Phantoms in the beam: built-in names (helix-holder, shepp-logan, brick-and-plate, sample-1, sample-2, "
                  "walnut) or ctk-phantom/1 files (.json); repeat to combine")
      ->capture_default_str();
  cmd->add_option("--holder", o->request.holder,
                  "The holder the scan declares and helix-holder draws: reference, thesis-first, or a ctk-holder/1 file")
      ->capture_default_str();
  auto* poses = cmd->add_option("--poses", o->request.poses, "Per-view matrices (ctk-geometry/1) instead of a robot trajectory")
                    ->check(CLI::ExistingFile);
  cmd->add_option("--trajectory", o->request.trajectory,
                  "Robot trajectory: circular (joint 7 orbit), spherical (HEALPix directions), cap (--cap-deg band of directions "
                  "about the holder axis while it spins), random (uniform directions from --seed)")
      ->check(CLI::IsMember({"circular", "spherical", "cap", "random"}))
      ->capture_default_str()
      ->excludes(poses);
  cmd->add_option("--views", o->request.views, "Views of a circular, cap or random trajectory")
      ->check(CLI::Range(1, 100000))
      ->capture_default_str();
  cmd->add_option("--cap-deg", o->cap_deg, "A cap trajectory's band: least and greatest angle between beam and holder axis")
      ->expected(2)
      ->check(CLI::Range(0.0, 180.0))
      ->capture_default_str();
  cmd->add_option("--nside", o->request.nside, "HEALPix resolution of a spherical trajectory (12 nside^2 directions)")
      ->check(CLI::Range(1, 64))
      ->capture_default_str();
  cmd->add_option("--cols", o->request.cols, "Detector columns")->check(CLI::Range(1, 100000))->capture_default_str();
  cmd->add_option("--rows", o->request.rows, "Detector rows")->check(CLI::Range(1, 100000))->capture_default_str();
  cmd->add_option("--pitch", o->request.pitch_mm, "Pixel pitch (mm)")->check(positive_number)->capture_default_str();
  cmd->add_option("--sdd", o->request.sdd_mm, "Source-to-detector distance (mm)")->check(positive_number)->capture_default_str();
  cmd->add_option("--sod", o->request.sod_mm, "Source-to-isocentre distance (mm)")->check(positive_number)->capture_default_str();
  cmd->add_option("--supersampling", o->request.supersampling, "s x s rays per pixel")
      ->check(CLI::Range(1, 16))
      ->capture_default_str();
  cmd->add_option("--output", o->output, "counts: 16-bit TIFF with flat and dark; line-integrals: float EXR, noise-free")
      ->check(CLI::IsMember({"counts", "line-integrals"}))
      ->capture_default_str();
  cmd->add_option("--flat-counts", o->request.counts.flat_counts, "Mean counts above dark, open beam")
      ->check(CLI::Range(1.0, 65000.0))
      ->capture_default_str();
  cmd->add_option("--dark-counts", o->request.counts.dark_counts, "Dark offset (counts)")
      ->check(CLI::Range(0.0, 10000.0))
      ->capture_default_str();
  cmd->add_option("--kvp", o->request.kvp, "Polychromatic rays from a tube at this voltage (Kramers spectrum; beam hardening)")
      ->check(CLI::Range(16.0, 150.0));
  cmd->add_option("--filter-al-mm", o->request.filter_al_mm, "Aluminium filter of the polychromatic spectrum")
      ->check(non_negative_number)
      ->capture_default_str();
  cmd->add_option("--robot-noise-mm", o->request.robot_noise.translation_mm, "Pose repeatability, RMS translation (0: off)")
      ->check(non_negative_number)
      ->capture_default_str();
  cmd->add_option("--robot-noise-deg", o->request.robot_noise.rotation_deg, "Pose repeatability, RMS rotation (0: off)")
      ->check(non_negative_number)
      ->capture_default_str();
  cmd->add_option("--seed", o->request.seed, "Random seed (noise, effects)")->capture_default_str();

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
  auto* jitter = cmd->add_option("--sphere-jitter-mm", o->sphere_jitter_mm,
                                 "A printed holder: every sphere off its declared centre, Gaussian of this sigma per axis")
                     ->check(CLI::Range(1e-6, 10.0))
                     ->group(effects);
  cmd->add_option("--holder-seed", o->holder_seed, "The printed holder's own seed (scans of one holder share it)")
      ->needs(jitter)
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
  const std::string nuisances = "Lab nuisances (no effect names them)";
  cmd->add_option("--scatter", o->scatter_fraction,
                  "Scatter: a smooth background, this fraction of the flat's transmitted signal")
      ->check(CLI::Range(0.0, 1.0))
      ->group(nuisances);
  cmd->add_option("--detector-psf-px", o->detector_psf_px, "Detector PSF, Gaussian sigma (px), on the intensities")
      ->check(non_negative_number)
      ->group(nuisances);
  cmd->add_option("--focal-spot-mm", o->focal_spot_mm, "Focal spot FWHM (mm): a penumbra of FWHM times (magnification - 1)")
      ->check(non_negative_number)
      ->group(nuisances);
  cmd->add_option("--lag", o->detector_lag, "Detector lag: this fraction of each view is the previous view's signal")
      ->check(CLI::Range(0.0, 0.99))
      ->group(nuisances);
  cmd->add_option("--robot-clusters-mm", o->robot_clusters_mm,
                  "The flange lands in one of two places per target this far apart (one direction per scan)")
      ->check(non_negative_number)
      ->group(nuisances);
  cmd->add_option("--robot-droop-mm-per-m", o->robot_droop_mm_per_m,
                  "The flange sinks this much per metre of horizontal reach from the base (gravity on the arm)")
      ->check(non_negative_number)
      ->group(nuisances);
  cmd->callback([o] { run_simulate(*o); });
}

}  // namespace ctk::tools

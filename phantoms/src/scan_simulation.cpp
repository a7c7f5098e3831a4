#include "ctk/phantoms/scan_simulation.hpp"

#include <atomic>
#include <optional>
#include <random>

#include "ctk/core/atomic_write.hpp"
#include "ctk/core/output_set.hpp"
#include "ctk/core/parallel.hpp"
#include "ctk/geom/scan.hpp"
#include "ctk/phantoms/builtin_phantoms.hpp"
#include "ctk/phantoms/render.hpp"

namespace ctk {

namespace fs = std::filesystem;

namespace {

ScanDescription declared_scan(const ScanSimulation& sim, const fs::path& folder, int view_count) {
  ScanDescription scan;
  scan.written_by_run = this_run_id();
  scan.folder = folder;
  scan.detector = sim.setup.detector;
  scan.principal_point_px = sim.setup.principal_point_px;
  scan.source_to_detector_mm = sim.setup.source_to_detector_mm;
  const bool counts = sim.output == SimulatedOutput::counts;
  scan.projections.files_pattern = counts ? "projections/proj_%04d.tif" : "projections/proj_%04d.exr";
  scan.projections.count = view_count;
  scan.projections.kind = counts ? ProjectionKind::counts : ProjectionKind::line_integrals;
  if (counts) {
    scan.projections.flat = {"flat.tif"};
    scan.projections.dark = {"dark.tif"};
  }
  if (sim.poses) {
    scan.matrices = MatricesPoseSource{"poses.json", *sim.poses};
  } else {
    PandaPoseSource panda;
    panda.joints_csv = "joints.csv";
    panda.T_camera_base = sim.setup.T_camera_base;
    panda.T_flange_holder = sim.setup.T_flange_holder;
    for (std::size_t v = 0; v < sim.trajectory.size(); ++v)
      if (sim.trajectory[v].joints) panda.joints.add(static_cast<int>(v), *sim.trajectory[v].joints);
    scan.panda = panda;
  }
  if (sim.with_holder) scan.holder = sim.holder;
  return scan;
}

// One acquired view, from the phantom to the file.
std::size_t write_projection(const ScanSimulation& sim, const Phantom& phantom, const TrueView& view, const TrueView* previous,
                             const RenderOptions& render, const fs::path& file) {
  std::size_t saturated = 0;
  const Image image = simulated_image(sim, phantom, view, render, &saturated, previous);
  if (sim.output == SimulatedOutput::line_integrals)
    write_image_float(image, file);
  else
    write_image_uint16(image, file);
  return saturated;
}

void write_flat_and_dark(const ScanSimulation& sim, const fs::path& folder) {
  const OpenBeamFrames frames = open_beam_frames(sim);
  write_image_uint16(frames.flat, folder / "flat.tif");
  write_image_uint16(frames.dark, folder / "dark.tif");
}

}  // namespace

namespace {

// One view's line integrals with its own blur and spurious blobs.
Image view_line_integrals(const ScanSimulation& sim, const Phantom& phantom, const TrueView& view, const RenderOptions& render) {
  Image image = render_line_integrals(phantom, *view.P, sim.setup.detector, render);
  if (view.blur_sigma_px > 0) blur_image(image, view.blur_sigma_px);
  for (const Blob& blob : view.blobs) add_blob(image, blob);
  return image;
}

// One view's noise-free signal (counts above dark) through the lab's nuisances: the detector's
// PSF, the focal spot's penumbra (its FWHM times the magnification less one, at the holder
// origin), scatter.
Image expected_signal(const ScanSimulation& sim, const Phantom& phantom, const TrueView& view, const RenderOptions& render) {
  Image image = view_line_integrals(sim, phantom, view, render);
  for (float& p : image.pixels) p = static_cast<float>(sim.counts.flat_counts * std::exp(-double(p)));
  const SimulationEffects& e = sim.effects;
  const double magnification = sim.setup.source_to_detector_mm / sim.setup.source_to_isocentre_mm;
  const double spot_px = e.focal_spot_mm ? *e.focal_spot_mm / 2.3548 * (magnification - 1) / sim.setup.detector.pitch_u_mm : 0.0;
  const double psf_px = e.detector_psf_px.value_or(0.0);
  apply_detector_response(image, std::hypot(spot_px, psf_px), e.scatter_fraction.value_or(0.0));
  return image;
}

bool has_detector_nuisances(const SimulationEffects& e) {
  return e.scatter_fraction || e.detector_psf_px || e.focal_spot_mm || e.detector_lag;
}

}  // namespace

Image simulated_image(const ScanSimulation& sim, const Phantom& phantom, const TrueView& view, const RenderOptions& render,
                      std::size_t* saturated, const TrueView* previous) {
  const bool nuisances = has_detector_nuisances(sim.effects) && sim.output == SimulatedOutput::counts;
  Image counts;
  if (!nuisances) {
    Image image = view_line_integrals(sim, phantom, view, render);
    if (sim.output == SimulatedOutput::line_integrals) return image;
    counts = expected_counts(image, sim.counts);
  } else {
    counts = expected_signal(sim, phantom, view, render);
    // Lag: what the previous frame left in the detector (its own holder when a sphere moves).
    if (sim.effects.detector_lag && previous && previous->P) {
      const Image before =
          expected_signal(sim, previous->holder ? simulated_phantom(sim, *previous->holder) : phantom, *previous, render);
      const auto lag = static_cast<float>(*sim.effects.detector_lag);
      for (std::size_t i = 0; i < counts.pixels.size(); ++i)
        counts.pixels[i] = (1 - lag) * counts.pixels[i] + lag * before.pixels[i];
    }
    for (float& c : counts.pixels) c += static_cast<float>(sim.counts.dark_counts);
  }
  // Noise differs per view but not with the thread count: one stream per (seed, view).
  std::seed_seq seq{static_cast<std::uint64_t>(sim.seed), static_cast<std::uint64_t>(view.index), std::uint64_t{0x5ca1ab1e}};
  std::mt19937_64 rng(seq);
  const std::size_t n = draw_counts(counts, sim.counts, rng);
  if (saturated) *saturated = n;
  return counts;
}

OpenBeamFrames open_beam_frames(const ScanSimulation& sim) {
  const Detector& d = sim.setup.detector;
  const std::size_t n = static_cast<std::size_t>(d.cols) * static_cast<std::size_t>(d.rows);
  return {Image{d.cols, d.rows, std::vector<float>(n, static_cast<float>(sim.counts.dark_counts + sim.counts.flat_counts))},
          Image{d.cols, d.rows, std::vector<float>(n, static_cast<float>(sim.counts.dark_counts))}};
}

Phantom simulated_phantom(const ScanSimulation& sim, const Holder& holder) {
  Phantom phantom{sim.with_holder ? "helix-holder + " + sim.sample.name : sim.sample.name, {}};
  if (sim.with_holder) phantom.add(helix_holder_phantom(holder));
  phantom.add(sim.sample);
  return phantom;
}

RenderOptions simulated_render_options(const ScanSimulation& sim) {
  return {sim.supersampling, sim.effects.detector_distortion, sim.spectrum};
}

SimulationReport simulate_scan(const ScanSimulation& sim, const fs::path& folder, const std::function<void(int, int)>& progress) {
  const TrueScan truth = make_true_scan(sim);
  const int view_count = static_cast<int>(truth.views.size());
  const ScanDescription scan = declared_scan(sim, folder, view_count);
  std::vector<std::string> names;
  names.reserve(static_cast<std::size_t>(view_count));
  for (int v = 0; v < view_count; ++v) names.push_back(scan.projections.file_name(v));

  const Phantom phantom = simulated_phantom(sim, truth.holder);
  const RenderOptions render = simulated_render_options(sim);

  fs::create_directories(folder / "projections");
  std::vector<int> acquired;
  for (const TrueView& v : truth.views)
    if (v.P) acquired.push_back(v.index);
  std::atomic<int> done{0};
  const int total = static_cast<int>(acquired.size());
  std::atomic<std::size_t> saturated_total{0};
  parallel_for_dynamic(total, [&](int i) {
    const TrueView& view = truth.views[static_cast<std::size_t>(acquired[static_cast<std::size_t>(i)])];
    std::optional<Phantom> moved;  // this view's own holder when a sphere moves during the scan
    if (view.holder) moved = simulated_phantom(sim, *view.holder);
    const TrueView* previous =
        i > 0 ? &truth.views[static_cast<std::size_t>(acquired[static_cast<std::size_t>(i - 1)])] : nullptr;
    saturated_total += write_projection(sim, moved ? *moved : phantom, view, previous, render, scan.projection_path(view.index));
    const int finished = ++done;
#pragma omp critical(ctk_simulation_progress)
    if (progress) progress(finished, total);
  });

  if (sim.output == SimulatedOutput::counts) write_flat_and_dark(sim, folder);
  write_geometry(true_geometry(sim, truth, names), folder / "truth-geometry.json");
  write_text_atomically(folder / "truth.json", truth_to_json(sim, truth, "truth-geometry.json").dump(2) + "\n");
  if (scan.panda) scan.panda->joints.write(folder / scan.panda->joints_csv);
  if (scan.matrices) write_geometry(scan.matrices->geometry, folder / scan.matrices->file);
  write_scan(scan, folder / "scan.json");
  return {view_count, total, saturated_total.load()};
}

}  // namespace ctk

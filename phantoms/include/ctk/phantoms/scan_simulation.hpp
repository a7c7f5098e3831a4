#pragma once
// Writes a simulated scan folder: projections (16-bit counts with flat and dark, or float EXR
// line integrals), joints.csv, scan.json declaring only the nominal setup (scan-format.md), and
// the truth (truth.json, truth-geometry.json). Every file is written atomically and scan.json
// last, so an interrupted run never leaves a scan that looks complete.
#include <cstddef>
#include <filesystem>
#include <functional>

#include "ctk/phantoms/render.hpp"
#include "ctk/phantoms/true_scan.hpp"

namespace ctk {

struct SimulationReport {
  int views = 0;  // in the scan (acquired or not)
  int views_acquired = 0;
  std::size_t saturated_pixels = 0;
};

/// The averaged, noise-free flat (dark + flat counts) and dark frames of a counts scan.
struct OpenBeamFrames {
  Image flat, dark;
};
OpenBeamFrames open_beam_frames(const ScanSimulation& simulation);

/// Everything in the beam: the holder (when in the beam; the true one, or a view's own when a
/// sphere moves) and the sample.
Phantom simulated_phantom(const ScanSimulation& simulation, const Holder& holder);
RenderOptions simulated_render_options(const ScanSimulation& simulation);
/// One acquired view's image as the detector delivers it: counts (noise drawn from the seed and
/// the view index) or noise-free line integrals, per `simulation.output`. Counts carry the lab's
/// nuisances the effects ask for (PSF, focal spot, scatter; lag from `previous`, the view acquired before).
Image simulated_image(const ScanSimulation& simulation, const Phantom& phantom, const TrueView& view, const RenderOptions& render,
                      std::size_t* saturated = nullptr, const TrueView* previous = nullptr);

/// `progress(done, total)` is called as views are written (from one thread at a time).
SimulationReport simulate_scan(const ScanSimulation& simulation, const std::filesystem::path& folder,
                               const std::function<void(int, int)>& progress = {});

}  // namespace ctk

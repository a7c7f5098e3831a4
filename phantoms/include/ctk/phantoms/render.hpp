#pragma once
// Exact projections of an analytic phantom: per detector pixel, rays from the source through
// s x s sub-pixel points, each ray's line integral summed over the primitives in closed form.
// The pixel reports what a detector measures: the mean transmitted intensity over its area,
// as a line integral -log(mean(exp(-p))) (partial-volume effect included; s = 1 gives the
// line integral through the pixel centre).
//
// With a spectrum the rays are polychromatic: each energy bin attenuates by the primitives'
// materials at that energy, and the pixel reports -log of the signal-weighted transmission, so
// thick or dense parts harden the beam (their line integral grows less than their path).
#include <optional>
#include <vector>

#include "ctk/core/image_io.hpp"
#include "ctk/core/volume.hpp"
#include "ctk/geom/detector.hpp"
#include "ctk/geom/projection_matrix.hpp"
#include "ctk/phantoms/phantom.hpp"
#include "ctk/phantoms/xray_spectrum.hpp"

namespace ctk {

struct RenderOptions {
  int supersampling = 2;                       // s: s x s rays per pixel
  std::optional<RadialDistortion> distortion;  // the detector's, applied to where rays land
  std::optional<XraySpectrum> spectrum;        // absent: monochromatic at the reference energy
  void validate() const;                       // std::invalid_argument naming the field
};

/// Line-integral image (cols x rows) of `phantom` for the view P (holder frame -> pixels).
Image render_line_integrals(const Phantom& phantom, const ProjectionMatrix& P, const Detector& detector,
                            const RenderOptions& options = {});

/// The truth on a voxel grid: each voxel the mean attenuation at 2 x 2 x 2 points inside it (a
/// face through the voxel counts by the share of points on each side).
Volume voxelised(const Phantom& phantom, const VolumeLayout& layout);

/// The truth split by the primitives' `material` (those without one share the empty name), in the
/// order each first appears: each share is its primitives alone, holes included (a hole is made of
/// the material it is cut from), and the shares add up to `voxelised(phantom, layout)`.
std::vector<MaterialVolume> voxelised_per_material(const Phantom& phantom, const VolumeLayout& layout);

}  // namespace ctk

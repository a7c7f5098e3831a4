#pragma once
// A sphere's centre from its whole projected profile: the line integrals through a ball are a
// disc's chord lengths, 2 A sqrt(R^2 - r^2), sitting on the (locally planar) background of the
// holder wall. Fitting that model by least squares weighs every pixel by how much it says about
// the centre (the steep rim most), where the centroid weighs the flat middle most; with the
// image noise of the scans that halves the centre's scatter.
#include "ctk/calib/sphere_detection.hpp"

namespace ctk {

struct ProfileFitOptions {
  double margin_px = 3.0;   // the window reaches this far beyond the sphere's rim
  int subsamples = 3;       // per pixel and axis: the model is averaged over the pixel's area
  double max_move_px = 1.0; // a fit moving further from its start is not trusted
};

/// Refines `detection.uv` (a centroid or better) for a sphere of projected radius about
/// `radius_px`. Radius, amplitude and background plane are fitted too. Returns false, leaving
/// `detection` untouched, when the window leaves the image, the fit fails or it moves too far.
bool refine_by_profile_fit(const Image& line_integrals, double radius_px, SphereDetection& detection,
                           const ProfileFitOptions& options = {});

}  // namespace ctk

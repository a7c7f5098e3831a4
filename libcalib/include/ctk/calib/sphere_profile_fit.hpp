#pragma once
// A sphere's centre from its whole projected profile: the line integrals through a ball are a
// disc's chord lengths, 2 A sqrt(R^2 - r^2), sitting on the (locally planar) background of the
// holder wall. Fitting that model by least squares weighs every pixel by how much it says about
// the centre (the steep rim most), where the centroid weighs the flat middle most; with the
// image noise of the reference scans that halves the centre's scatter. Where the background is
// known not to be planar (a sphere on the silhouette of the holder's wall), its known shape is
// added to the plane with a fitted scale. A polychromatic beam (or scatter) makes a ball's
// contrast fall where the background is higher; the scan's measured rate of that fall
// (contrast_loss.hpp) scales the chords pixel by pixel.
#include <functional>
#include <span>
#include <vector>

#include "ctk/calib/sphere_detection.hpp"

namespace ctk {

struct ProfileFitOptions {
  double margin_px = 3.0;    // the window reaches this far beyond the sphere's rim
  int subsamples = 3;        // per pixel and axis: the model is averaged over the pixel's area
  double max_move_px = 1.0;  // a fit moving further from its start is not trusted
  double contrast_loss = 0;  // the balls' relative contrast lost per unit of background line integral
  void validate() const;     // std::invalid_argument naming the field
};

/// A known shape of the background at an image position (pixel units), e.g. the path length
/// through the holder's wall. The fit averages it over each pixel and scales it.
using BackgroundShape = std::function<double(const Eigen::Vector2d& uv)>;

/// Refines `detection.uv` (a centroid or better) for a sphere of projected radius about
/// `radius_px`. Radius, amplitude, background plane and the scale of `shape` (when given) are
/// fitted too; `detection.strength` becomes the fitted ball's line integral summed over its disc.
/// Returns false, leaving `detection` untouched, when the window leaves the image, the fit fails
/// or it moves too far.
bool refine_by_profile_fit(const Image& line_integrals, double radius_px, SphereDetection& detection,
                           const ProfileFitOptions& options = {}, const BackgroundShape& shape = nullptr);

/// Spheres whose windows overlap, fitted together: one background, a centre, radius and amplitude
/// per ball. Returns which were refined; the others keep their start.
std::vector<bool> refine_cluster_by_profile_fit(const Image& line_integrals, double radius_px, std::span<SphereDetection> spheres,
                                                const ProfileFitOptions& options = {}, const BackgroundShape& shape = nullptr);

}  // namespace ctk

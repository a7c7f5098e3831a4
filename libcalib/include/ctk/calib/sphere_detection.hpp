#pragma once
// Finding the holder's spheres in one line-integral image: candidates are the local maxima of a
// difference-of-Gaussians tuned to the projected sphere size, kept when the image curves down in
// every direction there (a sphere is a bump; the tube's silhouette edges are ridges), each refined to a sub-pixel centre by an
// intensity-weighted centroid after removing a plane fitted to the surrounding ring.
// Where the background is not locally planar (looking along the holder's axis, the tube's end-on
// shadow is a ring a few sphere diameters wide with the spheres on its steep edge), the plane and
// the filters' wide Gaussian see the edge, not the sphere; a median over a window two
// sphere diameters across follows such edges and leaves the bumps, so it can be removed first.
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <vector>

#include "ctk/core/image_io.hpp"

namespace ctk {

struct SphereDetection {
  Eigen::Vector2d uv{0, 0};  // sub-pixel centre (pixel-centre convention of scan-format.md)
  double strength = 0;       // background-free line integral summed over the blob (mm * px^2)
  double response = 0;       // filter response at the candidate
};

struct DetectionOptions {
  double radius_px = 2.6;      // projected sphere radius
  double noise_sigmas = 5.0;   // response threshold, in robust noise deviations
  double min_roundness = 0.3;  // smaller / larger curvature: below, a ridge (a wall's edge)
  int max_candidates = 400;
  Eigen::AlignedBox2d region;  // the pixels searched, e.g. where a first guess puts the spheres
                               // with room for its error (empty: the whole image)
  /// Subtract a running median of the image before filtering, and take centroids on the
  /// remainder (steep non-planar backgrounds; the centres are coarser, about 0.3 px).
  bool edge_preserving_background = false;
  void validate() const;  // std::invalid_argument naming the field
};

/// `line_integrals` is one view's image; returns the detections, strongest first.
std::vector<SphereDetection> detect_spheres(const Image& line_integrals, const DetectionOptions& options);

/// The sub-pixel centre of a blob near `guess`: background plane from the ring between
/// radius + 2 and radius + 4, centroid of the positive remainder within radius + 1.5.
/// Returns false when the window leaves the image or holds no signal.
bool refine_centroid(const Image& line_integrals, const Eigen::Vector2d& guess, double radius_px, SphereDetection& out);

}  // namespace ctk

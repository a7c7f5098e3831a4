#pragma once
// A coarser detector: b x b pixels become one (a last partial row or column is dropped), and
// everything that addresses pixels follows, so that binned pixel (u', v') is the centre of the
// pixels it merges, u = b u' + (b - 1) / 2. The images themselves: binned_image (image_io.hpp).
#include "ctk/geom/detector.hpp"
#include "ctk/geom/geometry_file.hpp"
#include "ctk/geom/projection_matrix.hpp"

namespace ctk {

/// Throws std::invalid_argument for a factor below 1 or larger than the detector.
Detector binned_detector(const Detector& detector, int factor);
ProjectionMatrix binned_matrix(const ProjectionMatrix& P, int factor);
/// A fine pixel position on the binned detector, and back.
Eigen::Vector2d binned_pixel(const Eigen::Vector2d& fine_px, int factor);
Eigen::Vector2d unbinned_pixel(const Eigen::Vector2d& binned_px, int factor);
/// The same distortion in binned pixels: its centre moves as a pixel does, k1 grows by b^2.
RadialDistortion binned_distortion(const RadialDistortion& distortion, int factor);
RadialDistortion unbinned_distortion(const RadialDistortion& distortion, int factor);
/// Every view's matrix binned and the detector with them.
Geometry binned_geometry(const Geometry& geometry, int factor);

}  // namespace ctk

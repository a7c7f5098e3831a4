#pragma once
// Coarser detectors for quick reconstructions (view planning, previews): b x b pixels become one,
// and the matrices follow so the binned pixel (u', v') is the centre of the pixels it merges,
// u = b u' + (b - 1) / 2. A last partial row or column is dropped.
#include "ctk/geom/detector.hpp"
#include "ctk/geom/projection_matrix.hpp"
#include "ctk/core/image_io.hpp"

namespace ctk {

/// Throws std::invalid_argument for a factor below 1 or larger than the detector.
Detector binned_detector(const Detector& detector, int factor);
/// Mean of each b x b block (of line integrals, or of weights).
Image binned_image(const Image& image, int factor);
ProjectionMatrix binned_matrix(const ProjectionMatrix& P, int factor);

}  // namespace ctk

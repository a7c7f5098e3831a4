#pragma once
// The rotation axis' column from the data alone, for a full circular scan: every line through
// the object is measured twice, from source angles half a turn apart, so a fan-beam sinogram
// obeys p(beta, u) = p(beta + pi + 2 s gamma(u), 2 u0 - u) with gamma(u) = atan((u - u0) pitch /
// SDD) and s = +-1 by the rotation sense. The u0 that makes the two measurements of each line
// agree best is the column the axis projects to (on a centred orbit, the principal point's u). It
// needs no reconstruction, so it cross-checks the markerless loop's yardstick.
#include <cstdint>
#include <vector>

#include "ctk/core/projection_stack.hpp"
#include "ctk/geom/detector.hpp"
#include "ctk/recon/fdk.hpp"

namespace ctk {

/// One detector row over a circular scan: `values[view * cols + col]`, line integrals; view k at
/// source angle first_angle_rad + k step_rad (the sign of the step is not needed: both senses
/// are tried and the data choose).
struct FanSinogram {
  int views = 0, cols = 0;
  std::vector<float> values;
  double first_angle_rad = 0, step_rad = 0;
  double pitch_mm = 0, source_to_detector_mm = 0;
};

struct ConjugateRayEstimate {
  double u0_px = 0;
  double standard_error_px = 0;  // jackknife over blocks of views
  // From the first and third quarter turns, and from the second and fourth: disjoint measurements
  // (each conjugate pair lies within one), parted by whatever moves during the scan.
  double u0_quarters_px[2] = {0, 0};
  int sense = 0;            // s above: the one whose pairs agree (the other disagrees by far)
  double rms_mismatch = 0;  // between the two measurements of a line at u0, line-integral units
  double rms_mismatch_other_sense = 0;
  std::int64_t pairs = 0;  // pairs of measurements compared at u0
};

/// The row nearest `v0_px` of a circular scan's stack as a sinogram, the views' angles taken from
/// the fitted orbit. Throws std::invalid_argument when the views are not at equal steps.
FanSinogram row_sinogram(const ProjectionStack& b, const CircularTrajectory& orbit, const Detector& detector, double v0_px,
                         double source_to_detector_mm);

/// Searches u0 within `search_px` of `start_px` (a coarse scan of half-pixel steps, then a
/// parabola through tenth-pixel steps about the best). Throws std::invalid_argument when the
/// views do not cover a full turn or the sizes disagree.
ConjugateRayEstimate conjugate_ray_u0(const FanSinogram& sinogram, double start_px, double search_px = 30);

}  // namespace ctk

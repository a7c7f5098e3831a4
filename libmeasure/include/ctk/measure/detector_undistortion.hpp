#pragma once
// Projections taken through a radially distorted detector, resampled onto the pinhole grid the
// matrices describe. A point whose ideal projection is x was measured at
// RadialDistortion::measured_from_ideal(x), so the ideal image at pixel x is the measured image
// read there, bilinearly (OpenCV's remap, whose weights come from a table in steps of 1/32 px).
// Calibration undistorts sphere centres the same way; this makes the images agree with the same
// pinhole matrices.
#include <vector>

#include "ctk/geom/detector.hpp"

namespace ctk {

class DetectorUndistortion {
 public:
  DetectorUndistortion(int cols, int rows, const RadialDistortion& distortion);

  /// What to read where the measured position of an ideal pixel lies off the detector.
  enum class Outside {
    nearest_edge,  // the closest measured pixel (line integrals: no artificial edge)
    zero,          // nothing (weights: such pixels take no part in the fit)
  };
  /// `ideal` (cols x rows, row-major) from `measured`; the two must not overlap.
  void apply(const float* measured, float* ideal, Outside outside) const;

  /// The largest distance between an ideal pixel and where it was measured.
  double largest_shift_px() const { return largest_shift_px_; }
  /// Ideal pixels whose measured position lies off the detector.
  int pixels_measured_outside() const { return outside_; }

 private:
  int cols_, rows_;
  std::vector<float> measured_u_, measured_v_;  // per ideal pixel
  double largest_shift_px_ = 0;
  int outside_ = 0;
};

}  // namespace ctk

#pragma once
// A circular scan that ends where it began with a new exposure (the FleX-ray's view 3600 at
// 360 deg): its last row against its first says whether the object moved during the scan, which
// no estimate of the geometry from the same data can tell.
#include <cmath>
#include <optional>

#include "ctk/recon/conjugate_rays.hpp"

namespace ctk {

struct RepeatExposure {
  int last_view = 0;          // compared with view 0
  double shift_px = 0;        // the last row's shift along the row that best matches the first
  double shift_sigma_px = 0;  // its standard error from the noise left after the shift (Cramer-Rao)
  double rms_difference = 0;  // first against last, as measured (line-integral units)
  /// Moved when the rows are shifted by more than three standard errors of the shift.
  bool moved() const { return std::abs(shift_px) > 3 * shift_sigma_px; }
};

/// The comparison, when the views cover a full turn plus the repeat (the last view within half a
/// step of the first's angle plus 360 deg); std::nullopt otherwise.
std::optional<RepeatExposure> compare_repeat_exposure(const FanSinogram& sinogram);

}  // namespace ctk

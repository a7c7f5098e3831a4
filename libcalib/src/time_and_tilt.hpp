#pragma once
// Whether a scan's trajectory lets a drift in time be told from a load that follows gravity: on a
// cap swept from its rim to its pole the holder's tilt changes with the view index, and a drift
// that grows with time looks like a sag that grows with the tilt. Where the two move together the
// diagnosis names both (confounded_with, the load's note) instead of choosing one.
#include "ctk/calib/scan_model.hpp"

namespace ctk {

struct TimeAndTilt {
  /// Pearson correlation, over the views with joints, of the view index and the sine of the
  /// holder axis' angle to the vertical (what a cantilever's sag scales with); 0 when the tilt
  /// does not change (a joint-7 orbit keeps it) or fewer than 3 views have joints.
  double correlation = 0;
  /// At 0.9 the tilt accounts for 81 % of the time order's variance: what is left to tell a
  /// drift from a sag is a fifth of the scan's lever arm.
  static constexpr double kConfounded = 0.9;
  bool confounded() const { return std::abs(correlation) >= kConfounded; }
};

TimeAndTilt time_and_tilt(const ScanObservations& observations);

}  // namespace ctk

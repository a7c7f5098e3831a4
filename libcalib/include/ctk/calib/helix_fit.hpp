#pragma once
// A helix fitted to measured sphere centres (an orthogonal-distance fit in Ceres): the axis
// (its tilt and where it crosses w = 0), radius, turn per millimetre and phase, each centre's
// place along the curve free, and each centre's deviation from the fitted curve. What a lab
// compares with its holder's drawing; the holder frame itself stays the declared one.
#include <Eigen/Core>
#include <vector>

#include "ctk/geom/helix.hpp"

namespace ctk {

struct HelixFit {
  Helix helix;                                // in the fitted axis' own frame
  Eigen::Vector2d axis_tilt_rad{0, 0};        // the axis turned about u, then v, from the holder's w
  Eigen::Vector2d axis_offset_mm{0, 0};       // where the axis crosses w = 0 (u, v)
  std::vector<double> tau_mm;                 // each centre's place along the axis
  std::vector<Eigen::Vector3d> deviation_mm;  // centre minus its nearest point of the curve (holder frame)
  double rms_deviation_mm = 0;                // 3-D RMS over the centres
  bool converged = false;

  /// The fitted curve's point at tau, in the holder frame.
  Eigen::Vector3d at(double tau) const;
};

/// Fits the helix through `centres` (at least 6) starting from `start` (the declared one).
HelixFit fit_helix(const std::vector<Eigen::Vector3d>& centres, const Helix& start);

}  // namespace ctk

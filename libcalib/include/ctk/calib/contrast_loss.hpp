#pragma once
// A polychromatic beam hardens as it crosses the holder's wall and the sample, and scatter adds a
// smooth background: both make a ball's contrast over its background fall where that background
// is higher. On the wall's silhouette the background rises steeply across a ball, so a fit that
// ignores this leans the centre towards the thinner side, a bias that follows the silhouette: on
// an orbit about the holder's axis it stays on the same detector columns and looks like a radial
// distortion (docs/design/loop.md). The fall's rate is one number per scan (per unit of background
// line integral, the balls' chords scaled by 1 - rate (background - the window's reference));
// measured as the rate at which a sample of views' spheres agree best with rigid poses.
#include <functional>
#include <nlohmann/json.hpp>
#include <vector>

#include "ctk/calib/scan_calibration.hpp"

namespace ctk {

struct ContrastLossMeasurement {
  double rate = 0;                       // best agreement, per unit background line integral
  double sigma = 0;                      // its standard error (the agreement's curvature)
  bool used = false;                     // measured above zero: calibration applies it
  int views = 0;                         // sample views calibrated at every trial rate
  int spheres = 0;                       // (view, sphere) pairs every trial used
  std::vector<double> trial_rates;       // the rates tried
  std::vector<double> mean_squared_px2;  // each trial's mean squared reprojection residual per sphere
};

/// Up to `count` views spread evenly over a scan of `projections` views.
std::vector<int> contrast_sample_views(int projections, int count = 24);

/// Calibrates the sample with `CalibrationOptions::contrast_loss` set to each trial rate (0 and 0.2,
/// then 0.2 further while the last agrees better, up to kMostContrastLoss; then half a step either
/// side of the best, or above 0 when 0 is best) and places the rate by a parabola through the best
/// trial and its neighbours. The agreement is the mean squared reprojection residual over the
/// (view, sphere) pairs every trial used. A ball's contrast only falls where more is in the way, so
/// a vertex below zero gives 0 (not used). The rate is used whenever it is measured above zero: a
/// threshold on its significance left a 2.9-sigma loss unmodelled and its bias accepted as a
/// distortion. `calibrate_sample` calibrates the same views each time with the options given
/// (image-only poses).
ContrastLossMeasurement measure_contrast_loss(const std::function<ScanCalibration(const CalibrationOptions&)>& calibrate_sample,
                                              const CalibrationOptions& options);

/// {"rate_per_line_integral", "sigma", "used", "views", "spheres", "trials": [{"rate", "mean_squared_px2"}]}.
nlohmann::json to_json(const ContrastLossMeasurement& m);

/// One line saying what was measured and whether it is applied.
std::string contrast_loss_line(const ContrastLossMeasurement& m);

}  // namespace ctk

#pragma once
// Refitting the scan model jointly over many views (a bundle adjustment in Ceres): every view
// keeps its own pose, tied to where the robot model puts it by the robot's repeatability (a
// prior at the flange), while the chosen effects' parameters are shared by all views. The image
// residual of each matched sphere and the prior of each view are in units of their noise, so a
// view's cost is a chi-square. Gauge: the sphere offsets cannot move, turn or scale the declared
// sphere list as a whole (that would be a holder mount or a depth change); it is fixed by
// constraints on their sums.
#include <Eigen/Core>
#include <vector>

#include "ctk/calib/scan_model.hpp"
#include "ctk/core/statistics.hpp"

namespace ctk {

struct ScanModelFit {
  EffectParameters parameters;
  std::vector<Rigid> poses;                               // per fitted view, in the order of `views`
  std::vector<double> cost;                               // chi-square per view (image + prior)
  std::vector<double> image_sq_px;                        // sum of squared image residuals per view (px^2)
  std::vector<int> residual_count;                        // image residuals per view (2 per sphere)
  std::vector<std::vector<Eigen::Vector2d>> residual_px;  // measured - model, per view and sphere
  Eigen::MatrixXd covariance;                             // of the active effects' parameters, in fit order (may be empty)
  std::vector<int> covariance_offsets;                    // where each active effect starts in it
  bool converged = false;

  /// Image RMS per sphere (px): the image residuals of every view, 2 per sphere.
  double image_rms_px() const;
};

/// Fits the poses of `views` (indices into observations.views) and the parameters of `active`,
/// starting from `start`; the other effects stay at their values in `start`.
ScanModelFit fit_scan_model(const ScanObservations& observations, const std::vector<Effect>& active,
                            const std::vector<std::size_t>& views, const EffectParameters& start, bool with_covariance = false);

/// Every view of `views` alone with the model fixed: its pose from its spheres and the robot
/// prior (the held-out test).
ScanModelFit fit_view_poses(const ScanObservations& observations, const EffectParameters& model,
                            const std::vector<std::size_t>& views);

/// Number of parameters an effect adds (sphere offsets: 3 per sphere).
int parameter_count(Effect e, const ScanObservations& observations);

/// How far the effect `active[slot]` of a fit with covariance stands from none: the Wald statistic
/// of the parameters that measure its size (all but a distortion's centre, which means nothing
/// without a distortion) against their marginal covariance. Zero degrees of freedom when the fit
/// has no covariance.
WaldStatistic effect_strength(const ScanModelFit& fit, const std::vector<Effect>& active, std::size_t slot);

}  // namespace ctk

#pragma once
// How the spheres' contrast falls with the background behind them, measured on the scan itself.
// Behind the holder's wall (and a sample) a polychromatic beam is harder, and scatter is a larger
// share of what reaches the detector, so a ball adds less line integral there: its fitted
// amplitude a (line integral per unit chord) follows a = a0 (1 - h b) over the background line
// integral b at its centre. Across one ball the same loss makes the side over thicker wall
// fainter, and the profile fit's centre leans to the thinner side (a bias that follows the wall's
// silhouette: on a joint-7 orbit it stays on the same detector columns and looks like a radial
// distortion). With h measured over many balls and views, the profile fit scales each ball's
// chords by 1 - h (b - b at the ball) (sphere_profile_fit.hpp).
#include <Eigen/Core>
#include <vector>

namespace ctk {

struct BallContrast {
  double hardening = 0;          // h: contrast loss per unit background line integral
  double sigma = 0;              // its standard error
  double amplitude_at_zero = 0;  // a0
  int balls = 0;                 // (background, amplitude) pairs the fit kept
  /// Used when h is above 0 by more than three standard errors (and a physical contrast loss).
  bool significant() const { return balls >= 20 && hardening > 3 * sigma && hardening < 1; }
};

/// Robust straight-line fit of amplitude over background (pairs (b, a)): least squares, pairs
/// beyond 4 robust deviations of the residuals dropped, fitted again.
BallContrast fit_ball_contrast(const std::vector<Eigen::Vector2d>& background_amplitude);

}  // namespace ctk

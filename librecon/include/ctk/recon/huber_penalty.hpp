#pragma once
// An edge-preserving penalty: lambda times the sum, over every pair of neighbouring voxels (along
// x, y and z), of the Huber function of their difference,
//   psi(t) = t^2 / 2 for |t| <= delta,  delta |t| - delta^2 / 2 beyond,
// quadratic for the small differences of noise and linear (total variation's) for the steps of
// edges, which it then does not smooth away. delta is in the volume's units (attenuation per mm):
// differences well below it are noise, well above it edges. Minimised by OS-SQS (os_sqs.hpp),
// whose separable surrogate needs each voxel's curvature at the current volume: with the
// half-quadratic bound psi(t) <= psi(s) + psi'(s) (t - s) + w(s) (t - s)^2 / 2, w = psi'(s) / s
// (at most 1), a pair's term splits between its two voxels as 2 w each (De Pierro).
#include "ctk/core/volume.hpp"

namespace ctk {

struct HuberPenalty {
  double lambda = 0;
  double delta = 0;       // > 0
  void validate() const;  // std::invalid_argument naming the field
};

/// lambda * sum over neighbour pairs of psi(x_i - x_j)
double huber_penalty_value(const HuberPenalty& penalty, const Volume& x);

/// gradient += lambda d/dx (sum psi); curvature = lambda * sum over each voxel's neighbours of 2 w.
void add_huber_gradient_and_curvature(const HuberPenalty& penalty, const Volume& x, Volume& gradient, Volume& curvature);

}  // namespace ctk

#include "ctk/recon/huber_penalty.hpp"

#include <cmath>

#include "ctk/core/error.hpp"
#include "neighbour_pairs.hpp"

namespace ctk {

namespace {

double psi(double t, double delta) {
  const double a = std::abs(t);
  return a <= delta ? 0.5 * t * t : delta * a - 0.5 * delta * delta;
}
double psi_derivative(double t, double delta) { return std::abs(t) <= delta ? t : (t > 0 ? delta : -delta); }
double weight(double t, double delta) { return std::abs(t) <= delta ? 1.0 : delta / std::abs(t); }  // psi'(t) / t

}  // namespace

void HuberPenalty::validate() const {
  require_option(lambda >= 0 && std::isfinite(lambda), "HuberPenalty.lambda", "a finite number of at least 0", lambda);
  require_option(delta > 0 && std::isfinite(delta), "HuberPenalty.delta", "a finite positive number (volume units)", delta);
}

double huber_penalty_value(const HuberPenalty& p, const Volume& x) {
  return p.lambda * detail::sum_over_neighbour_pairs(x, [&](double d) { return psi(d, p.delta); });
}

void add_huber_gradient_and_curvature(const HuberPenalty& p, const Volume& x, Volume& gradient, Volume& curvature) {
  detail::for_each_voxel_with_its_neighbours(x, [&](std::size_t at, const double* d, int count) {
    double g = 0, c = 0;
    for (int m = 0; m < count; ++m) {
      g += psi_derivative(d[m], p.delta);
      c += 2 * weight(d[m], p.delta);
    }
    gradient.data[at] += static_cast<float>(p.lambda * g);
    curvature.data[at] = static_cast<float>(p.lambda * c);
  });
}

}  // namespace ctk

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
  const auto& n = x.layout.size;
  const auto stride = x.layout.strides();
#pragma omp parallel for schedule(static)
  for (int k = 0; k < n[2]; ++k)
    for (int j = 0; j < n[1]; ++j)
      for (int i = 0; i < n[0]; ++i) {
        const std::size_t at = x.index(i, j, k);
        const int index[3] = {i, j, k};
        double g = 0, c = 0;
        for (int a = 0; a < 3; ++a) {
          const std::size_t s = static_cast<std::size_t>(stride[a]);
          if (index[a] > 0) {
            const double t = double(x.data[at]) - x.data[at - s];
            g += psi_derivative(t, p.delta);
            c += 2 * weight(t, p.delta);
          }
          if (index[a] + 1 < n[a]) {
            const double t = double(x.data[at]) - x.data[at + s];
            g += psi_derivative(t, p.delta);
            c += 2 * weight(t, p.delta);
          }
        }
        gradient.data[at] += static_cast<float>(p.lambda * g);
        curvature.data[at] = static_cast<float>(p.lambda * c);
      }
}

}  // namespace ctk

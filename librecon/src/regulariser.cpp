#include "ctk/recon/regulariser.hpp"

#include <stdexcept>

#include "neighbour_pairs.hpp"
#include "vector_ops.hpp"

namespace ctk {

const char* to_string(Regulariser r) { return r == Regulariser::identity ? "identity" : "gradient"; }

Regulariser regulariser_from_string(const std::string& name) {
  for (Regulariser r : {Regulariser::identity, Regulariser::gradient})
    if (name == to_string(r)) return r;
  throw std::invalid_argument("regulariser: expected identity or gradient, got '" + name + "'");
}

double regulariser_value(Regulariser r, const Volume& x) {
  if (r == Regulariser::identity) return 0.5 * detail::dot(x.data, x.data);
  return 0.5 * detail::sum_over_neighbour_pairs(x, [](double d) { return d * d; });
}

void add_regulariser_normal(Regulariser r, double lambda, const Volume& x, Volume& out) {
  if (lambda == 0) return;
  if (r == Regulariser::identity) {
    detail::axpy(lambda, x.data, out.data);
    return;
  }
  // G'G is the negative Laplacian with zero flux across the boundary: per axis, each neighbour
  // present contributes (x_here - x_neighbour).
  detail::for_each_voxel_with_its_neighbours(x, [&](std::size_t at, const double* d, int count) {
    double s = 0;
    for (int m = 0; m < count; ++m) s += d[m];
    out.data[at] += static_cast<float>(lambda * s);
  });
}

}  // namespace ctk

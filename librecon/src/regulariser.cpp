#include "ctk/recon/regulariser.hpp"

#include "neighbour_pairs.hpp"
#include "vector_ops.hpp"

namespace ctk {

const char* to_string(Regulariser r) { return r == Regulariser::identity ? "identity" : "gradient"; }

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
  const auto& n = x.layout.size;
  const auto stride = x.layout.strides();
#pragma omp parallel for schedule(static)
  for (int k = 0; k < n[2]; ++k)
    for (int j = 0; j < n[1]; ++j)
      for (int i = 0; i < n[0]; ++i) {
        const std::size_t at = x.index(i, j, k);
        const int index[3] = {i, j, k};
        double s = 0;
        for (int a = 0; a < 3; ++a) {
          if (index[a] > 0) s += double(x.data[at]) - x.data[at - static_cast<std::size_t>(stride[a])];
          if (index[a] + 1 < n[a]) s += double(x.data[at]) - x.data[at + static_cast<std::size_t>(stride[a])];
        }
        out.data[at] += static_cast<float>(lambda * s);
      }
}

}  // namespace ctk

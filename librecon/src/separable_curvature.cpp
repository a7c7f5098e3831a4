#include "ctk/recon/separable_curvature.hpp"

#include <algorithm>

#include "vector_ops.hpp"

namespace ctk {

Volume separable_data_curvature(const ProjectionOperator& A, const ProjectionStack* weights,
                                const std::vector<std::vector<int>>& subsets) {
  Volume ones(A.domain()), D(A.domain()), part_curvature(A.domain());
  std::fill(ones.data.begin(), ones.data.end(), 1.0f);
  const auto add_part = [&](const ProjectionOperator& part, const std::vector<int>* views) {
    ProjectionStack A1;
    part.apply(ones, A1);
    if (weights) {
      if (views) {
        ProjectionStack w;
        detail::gather_views(*weights, *views, w);
        detail::weighted_copy(A1.data, w.data, A1.data);
      } else {
        detail::weighted_copy(A1.data, weights->data, A1.data);
      }
    }
    part.apply_adjoint(A1, part_curvature);
    detail::axpy(1.0, part_curvature.data, D.data);
  };
  if (subsets.empty())
    add_part(A, nullptr);
  else
    for (const auto& s : subsets) add_part(*A.subset(s), &s);
  return D;
}

double separable_penalty_curvature(Regulariser regulariser, double lambda) {
  return lambda * (regulariser == Regulariser::identity ? 1.0 : 12.0);
}

}  // namespace ctk

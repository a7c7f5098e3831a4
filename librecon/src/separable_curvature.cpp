#include "ctk/recon/separable_curvature.hpp"

#include <algorithm>

#include "vector_ops.hpp"

namespace ctk {

Volume separable_data_curvature(const ProjectionOperator& A, const ProjectionStack* weights,
                                const std::vector<std::vector<int>>& subsets) {
  Volume ones(A.domain()), D(A.domain());
  std::fill(ones.data.begin(), ones.data.end(), 1.0f);
  ProjectionStack A1;
  if (subsets.empty()) {  // the whole operator at once: back projected straight into D
    A.apply(ones, A1);
    if (weights) detail::weighted_copy(A1.data, weights->data, A1.data);
    A.apply_adjoint(A1, D);
    return D;
  }
  Volume part_curvature(A.domain());
  ProjectionStack w;
  for (const auto& views : subsets) {
    const auto part = A.subset(views);
    part->apply(ones, A1);
    if (weights) {
      detail::gather_views(*weights, views, w);
      detail::weighted_copy(A1.data, w.data, A1.data);
    }
    part->apply_adjoint(A1, part_curvature);
    detail::axpy(1.0, part_curvature.data, D.data);
  }
  return D;
}

double separable_penalty_curvature(Regulariser regulariser, double lambda) {
  return lambda * (regulariser == Regulariser::identity ? 1.0 : 12.0);
}

}  // namespace ctk

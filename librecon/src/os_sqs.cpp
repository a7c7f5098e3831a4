#include "ctk/recon/os_sqs.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <stdexcept>
#include <string>

#include "ctk/core/error.hpp"
#include "ctk/recon/huber_penalty.hpp"
#include "ctk/recon/separable_curvature.hpp"
#include "vector_ops.hpp"

namespace ctk {

namespace {

// Throws unless `subsets` hold every view of 0 .. views-1 exactly once, and each subset holds a
// view on some rank (on an operator spread over ranks, a rank's part of a subset may be empty).
void require_partition(const ProjectionOperator& A, const std::vector<std::vector<int>>& subsets, int views) {
  if (subsets.empty()) throw std::invalid_argument("solve_os_sqs: no subsets");
  std::vector<int> seen(static_cast<std::size_t>(views), 0);
  for (const auto& s : subsets) {
    if (A.sum_over_range(static_cast<double>(s.size())) == 0) throw std::invalid_argument("solve_os_sqs: an empty subset");
    for (int v : s) {
      if (v < 0 || v >= views)
        throw std::invalid_argument("solve_os_sqs: view " + std::to_string(v) + " is not one of the " + std::to_string(views) +
                                    " views");
      if (seen[static_cast<std::size_t>(v)]++)
        throw std::invalid_argument("solve_os_sqs: view " + std::to_string(v) + " is in two subsets");
    }
  }
  for (int v = 0; v < views; ++v)
    if (!seen[static_cast<std::size_t>(v)])
      throw std::invalid_argument("solve_os_sqs: view " + std::to_string(v) + " is in no subset");
}

// r = A x - b, then its weighted half square sum, then r *= scale w (w empty: unit weights).
double weighted_residual(const ProjectionOperator& A, const Volume& x, const ProjectionStack& b, const FloatBuffer& w,
                         ProjectionStack& r, float scale = 1) {
  A.apply(x, r);
  detail::axpy(-1.0, b.data, r.data);
  const double half = 0.5 * detail::weighted_square_sum(r.data, w);
  if (!w.empty() || scale != 1) detail::weighted_copy(r.data, w, r.data, scale);
  return half;
}

}  // namespace

void OsSqsOptions::validate() const {
  require_option(epochs >= 0, "OsSqsOptions.epochs", "at least 0", epochs);
  require_option(lambda >= 0 && std::isfinite(lambda), "OsSqsOptions.lambda", "a finite number of at least 0", lambda);
  require_option(huber_delta >= 0 && std::isfinite(huber_delta), "OsSqsOptions.huber_delta",
                 "0 (a quadratic penalty) or a finite positive number", huber_delta);
}

// NOLINTNEXTLINE(readability-function-size): the subset loop in one piece: what it carries from step to step stays in view
SolverReport solve_os_sqs(const ProjectionOperator& A, const ProjectionStack& b, const ProjectionStack* weights, Volume& x,
                          const std::vector<std::vector<int>>& subsets, const OsSqsOptions& o,
                          const IterationCallback& on_iteration, const std::function<bool()>& stop_requested,
                          const StoppingRule& stopping) {
  o.validate();
  detail::require_problem_shapes("solve_os_sqs", A, b, x);
  if (weights && weights->data.size() != b.data.size())
    throw std::invalid_argument("solve_os_sqs: weights and line integrals differ in size");
  require_partition(A, subsets, b.views);
  const int M = static_cast<int>(subsets.size());
  static const FloatBuffer unit;
  auto start = std::chrono::steady_clock::now();

  std::vector<std::shared_ptr<const ProjectionOperator>> parts;
  parts.reserve(subsets.size());
  for (const auto& s : subsets) parts.push_back(A.subset(s));
  ProjectionStack b_part, w_part, r_part;  // one subset's data, weights and residual
  const auto load_part = [&](int s) {
    detail::gather_views(b, subsets[static_cast<std::size_t>(s)], b_part);
    if (weights) detail::gather_views(*weights, subsets[static_cast<std::size_t>(s)], w_part);
  };

  // The surrogate's curvature D = A'W A 1 + lambda c, subset by subset (no full-size stack).
  const Volume D = separable_data_curvature(A, weights, subsets);
  Volume g(x.layout);
  const bool huber = o.huber_delta > 0;
  const HuberPenalty penalty{o.lambda, o.huber_delta};
  const double curvature_of_penalty = huber ? 0.0 : separable_penalty_curvature(o.regulariser, o.lambda);
  Volume huber_curvature = huber ? Volume(x.layout) : Volume();  // follows the volume

  // x is the result so far (the last projected step), which the callback sees; with momentum the
  // gradients are taken at the extrapolated point y.
  Volume y = o.momentum ? x : Volume();
  Volume& at = o.momentum ? y : x;
  const auto cost_now = [&](double data_term, int epoch) {
    IterationLog log;
    log.iteration = epoch;
    log.data_term = data_term;
    log.regulariser_term = o.lambda == 0 ? 0.0
                           : huber       ? A.sum_over_domain(huber_penalty_value(penalty, x))
                                         : o.lambda * A.sum_over_domain(regulariser_value(o.regulariser, x));
    log.cost = log.data_term + log.regulariser_term;
    log.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    if (on_iteration) on_iteration(log);
    start = std::chrono::steady_clock::now();
    return log;
  };
  const auto exact_data_term = [&] {
    double sum = 0;
    for (int s = 0; s < M; ++s) {
      load_part(s);
      sum += weighted_residual(*parts[static_cast<std::size_t>(s)], x, b_part, weights ? w_part.data : unit, r_part);
    }
    return A.sum_over_range(sum);
  };

  SolverReport report;
  // A cold start's residual is -b: no projection needed for its cost.
  const bool cold =
      A.sum_over_domain(std::all_of(x.data.begin(), x.data.end(), [](float v) { return v == 0.0f; }) ? 0.0 : 1.0) == 0;
  report.iterations.push_back(cost_now(
      cold ? 0.5 * A.sum_over_range(detail::weighted_square_sum(b.data, weights ? weights->data : unit)) : exact_data_term(), 0));
  double t = 1;  // Nesterov's sequence
  const std::ptrdiff_t n = static_cast<std::ptrdiff_t>(x.data.size());
  for (int epoch = 1; epoch <= o.epochs; ++epoch) {
    double seen = 0;
    for (int s = 0; s < M; ++s) {
      load_part(s);
      const ProjectionOperator& As = *parts[static_cast<std::size_t>(s)];
      // The subset stands for the scan: its gradient times M (scaled on the subset's residual,
      // a few views, rather than on the volume), plus the penalty's.
      seen += weighted_residual(As, at, b_part, weights ? w_part.data : unit, r_part, static_cast<float>(M));
      As.apply_adjoint(r_part, g);
      if (huber)
        add_huber_gradient_and_curvature(penalty, at, g, huber_curvature);
      else
        add_regulariser_normal(o.regulariser, o.lambda, at, g);
      const double t_next = o.momentum ? 0.5 * (1 + std::sqrt(1 + 4 * t * t)) : 1;
      const float carry = static_cast<float>(o.momentum ? (t - 1) / t_next : 0);
#pragma omp parallel for schedule(static)
      for (std::ptrdiff_t i = 0; i < n; ++i) {
        const std::size_t k = static_cast<std::size_t>(i);
        const double d = double(D.data[k]) + (huber ? double(huber_curvature.data[k]) : curvature_of_penalty);
        float step = d > 0 ? static_cast<float>(double(at.data[k]) - double(g.data[k]) / d) : at.data[k];
        if (o.non_negative && step < 0) step = 0;
        if (o.momentum) y.data[k] = step + carry * (step - x.data[k]);
        x.data[k] = step;
      }
      t = t_next;
    }
    report.iterations.push_back(cost_now(o.exact_cost ? exact_data_term() : A.sum_over_range(seen), epoch));
    if (auto done = stopping ? stopping() : std::nullopt) {
      report.stop_reason = std::move(*done);
      return report;
    }
    if (epoch < o.epochs && stop_requested && stop_requested()) {
      report.stop_reason = kStoppedWithoutState;
      return report;
    }
  }
  report.stop_reason = "epoch limit (" + std::to_string(o.epochs) + ") reached, " + std::to_string(M) + " subsets";
  return report;
}

}  // namespace ctk

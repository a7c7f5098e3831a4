#include "ctk/recon/wls_cg.hpp"

#include <algorithm>
#include <chrono>
#include <utility>
#include <cmath>
#include <stdexcept>

#include "ctk/core/error.hpp"
#include "vector_ops.hpp"

namespace ctk {

using detail::axpy;
using detail::dot;

namespace {

double seconds_since(std::chrono::steady_clock::time_point t) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
}

}  // namespace

void WlsOptions::validate() const {
  require_option(iterations >= 0, "WlsOptions.iterations", "at least 0", iterations);
  require_option(tolerance >= 0 && tolerance < 1, "WlsOptions.tolerance", "a number in [0, 1)", tolerance);
  require_option(lambda >= 0 && std::isfinite(lambda), "WlsOptions.lambda", "a finite number of at least 0", lambda);
}

SolverReport solve_wls_cg(const ProjectionOperator& A, const ProjectionStack& b, const ProjectionStack* weights, Volume& x,
                          const WlsOptions& o, const IterationCallback& on_iteration, const Checkpointing* checkpointing) {
  detail::require_problem_shapes("solve_wls_cg", A, b, x);
  ProjectionStack residual(b.views, b.rows, b.cols);
  if (!(checkpointing && checkpointing->resume)) {  // a continued run takes its residual from the state
    const bool cold =
        A.sum_over_domain(std::all_of(x.data.begin(), x.data.end(), [](float v) { return v == 0.0f; }) ? 0.0 : 1.0) == 0;
    if (!cold) A.apply(x, residual);
    axpy(-1.0, b.data, residual.data);
  }
  return solve_wls_cg(A, b, weights, x, residual, o, on_iteration, checkpointing);
}

SolverReport solve_wls_cg(const ProjectionOperator& A, const ProjectionStack& b, const ProjectionStack* weights, Volume& x,
                          ProjectionStack& residual, const WlsOptions& o, const IterationCallback& on_iteration,
                          const Checkpointing* checkpointing) {
  o.validate();
  detail::require_problem_shapes("solve_wls_cg", A, b, x);
  if (weights && weights->data.size() != b.data.size())
    throw std::invalid_argument("solve_wls_cg: weights and line integrals differ in size");
  if (residual.data.size() != b.data.size())
    throw std::invalid_argument("solve_wls_cg: the residual and the line integrals differ in size");
  static const FloatBuffer unit;
  const FloatBuffer& w = weights ? weights->data : unit;
  auto start = std::chrono::steady_clock::now();

  ProjectionStack scratch(b.views, b.rows, b.cols);  // W r, then A d, then W A d
  Volume gradient(x.layout), direction(x.layout), H_direction(x.layout);
  SolverState* resume = checkpointing ? checkpointing->resume : nullptr;
  if (!resume) {
    detail::weighted_copy(residual.data, w, scratch.data);
    A.apply_adjoint(scratch, gradient);
    add_regulariser_normal(o.regulariser, o.lambda, x, gradient);
  }

  auto log_point = [&](int iteration, double g_norm, double g0_norm) {
    IterationLog log;
    log.iteration = iteration;
    log.data_term = 0.5 * A.sum_over_range(detail::weighted_square_sum(residual.data, w));
    log.regulariser_term = o.lambda > 0 ? o.lambda * A.sum_over_domain(regulariser_value(o.regulariser, x)) : 0.0;
    log.cost = log.data_term + log.regulariser_term;
    log.relative_gradient = g0_norm > 0 ? g_norm / g0_norm : 0.0;
    log.seconds = seconds_since(start);
    start = std::chrono::steady_clock::now();
    if (on_iteration) on_iteration(log);
    return log;
  };

  SolverReport report;
  double gg = 0, g0 = 0;
  int first = 1;
  if (resume) {
    check_solver_state(*resume, "wls-cg", {residual.data.size(), gradient.data.size(), direction.data.size()}, 2, x.layout);
    x.data = std::move(resume->x.data);
    residual.data = std::move(resume->vectors[0]);
    gradient.data = std::move(resume->vectors[1]);
    direction.data = std::move(resume->vectors[2]);
    gg = resume->scalars[0];
    g0 = resume->scalars[1];
    report.iterations = resume->log;
    first = resume->iteration + 1;
  } else {
    gg = A.sum_over_domain(dot(gradient.data, gradient.data));
    g0 = std::sqrt(gg);
    report.iterations.push_back(log_point(0, g0, g0));
    if (gg == 0) {
      report.stop_reason = "zero gradient at the start (nothing to fit)";
      return report;
    }
    for (std::size_t i = 0; i < direction.data.size(); ++i) direction.data[i] = -gradient.data[i];
  }

  for (int it = first; it <= o.iterations; ++it) {
    // Scratch holds A d for the residual update; H d = A' W A d + lambda G'G d.
    A.apply(direction, scratch);
    const double dHd_data = A.sum_over_range(detail::weighted_square_sum(scratch.data, w));
    ProjectionStack& Ad = scratch;
    // d'G'Gd = ||G d||^2 = 2 * (1/2 ||G d||^2): no extra volume needed.
    const double alpha_denominator =
        dHd_data + (o.lambda > 0 ? 2.0 * o.lambda * A.sum_over_domain(regulariser_value(o.regulariser, direction)) : 0.0);
    if (!(alpha_denominator > 0)) {
      report.stop_reason = "the search direction has no curvature (all views miss the volume?)";
      break;
    }
    const double alpha = gg / alpha_denominator;
    axpy(alpha, direction.data, x.data);
    axpy(alpha, Ad.data, residual.data);
    if (it == o.iterations && !o.gradient_after_last) {
      report.iterations.push_back(log_point(it, std::sqrt(gg), g0));
      break;
    }
    detail::weighted_copy(Ad.data, w, scratch.data);
    A.apply_adjoint(scratch, H_direction);
    add_regulariser_normal(o.regulariser, o.lambda, direction, H_direction);
    axpy(alpha, H_direction.data, gradient.data);
    const double gg_new = A.sum_over_domain(dot(gradient.data, gradient.data));
    report.iterations.push_back(log_point(it, std::sqrt(gg_new), g0));
    if (std::sqrt(gg_new) <= o.tolerance * g0) {
      report.stop_reason = "gradient fell below the tolerance after " + std::to_string(it) + " iterations";
      return report;
    }
    const double beta = gg_new / gg;
    gg = gg_new;
    const std::ptrdiff_t n = static_cast<std::ptrdiff_t>(direction.data.size());
#pragma omp parallel for schedule(static)
    for (std::ptrdiff_t i = 0; i < n; ++i) {
      const std::size_t k = static_cast<std::size_t>(i);
      direction.data[k] = static_cast<float>(-gradient.data[k] + beta * direction.data[k]);
    }
    if (checkpointing) {
      const bool stop = checkpointing->stop_requested && checkpointing->stop_requested();
      if (stop || (checkpointing->every > 0 && it % checkpointing->every == 0 && it < o.iterations))
        checkpointing->save({"wls-cg", it, report.iterations, x, {&residual.data, &gradient.data, &direction.data}, {gg, g0}});
      if (stop) {
        report.stop_reason = kStoppedOnRequest;
        return report;
      }
    }
  }
  if (report.stop_reason.empty()) report.stop_reason = "iteration limit (" + std::to_string(o.iterations) + ") reached";
  return report;
}

}  // namespace ctk

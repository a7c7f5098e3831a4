#include "ctk/recon/wls_cg.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <stdexcept>
#include <utility>

#include "ctk/core/error.hpp"
#include "ctk/recon/separable_curvature.hpp"
#include "vector_ops.hpp"

namespace ctk {

using detail::axpy;
using detail::dot;

namespace {

double seconds_since(std::chrono::steady_clock::time_point t) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
}

// 1 / (A'WA1 + lambda c) per voxel, 0 where nothing constrains the voxel (its gradient is 0 there).
FloatBuffer inverse_diagonal(const ProjectionOperator& A, const ProjectionStack* weights, const WlsOptions& o) {
  Volume D = separable_data_curvature(A, weights);
  const double c = separable_penalty_curvature(o.regulariser, o.lambda);
  const std::ptrdiff_t n = static_cast<std::ptrdiff_t>(D.data.size());
#pragma omp parallel for schedule(static)
  for (std::ptrdiff_t i = 0; i < n; ++i) {
    float& d = D.data[static_cast<std::size_t>(i)];
    const double total = double(d) + c;
    d = total > 0 ? static_cast<float>(1.0 / total) : 0.0f;
  }
  return std::move(D.data);
}

}  // namespace

const char* to_string(CgPreconditioner p) { return p == CgPreconditioner::diagonal ? "diagonal" : "none"; }

CgPreconditioner cg_preconditioner_from_string(const std::string& name) {
  if (name == "none") return CgPreconditioner::none;
  if (name == "diagonal") return CgPreconditioner::diagonal;
  throw std::invalid_argument("preconditioner: expected none or diagonal, got '" + name + "'");
}

void WlsOptions::validate() const {
  require_option(iterations >= 0, "WlsOptions.iterations", "at least 0", iterations);
  require_option(tolerance >= 0 && tolerance < 1, "WlsOptions.tolerance", "a number in [0, 1)", tolerance);
  require_option(lambda >= 0 && std::isfinite(lambda), "WlsOptions.lambda", "a finite number of at least 0", lambda);
}

SolverReport solve_wls_cg(const ProjectionOperator& A, const ProjectionStack& b, const ProjectionStack* weights, Volume& x,
                          const WlsOptions& o, const IterationCallback& on_iteration, const Checkpointing* checkpointing,
                          const StoppingRule& stopping) {
  detail::require_problem_shapes("solve_wls_cg", A, b, x);
  ProjectionStack residual(b.views, b.rows, b.cols);
  if (!(checkpointing && checkpointing->resume)) {  // a continued run takes its residual from the state
    const bool cold =
        A.sum_over_domain(std::all_of(x.data.begin(), x.data.end(), [](float v) { return v == 0.0f; }) ? 0.0 : 1.0) == 0;
    if (!cold) A.apply(x, residual);
    axpy(-1.0, b.data, residual.data);
  }
  return solve_wls_cg(A, b, weights, x, residual, o, on_iteration, checkpointing, stopping);
}

// NOLINTNEXTLINE(readability-function-size): the CG recurrence in one piece: what it carries from step to step stays in view
SolverReport solve_wls_cg(const ProjectionOperator& A, const ProjectionStack& b, const ProjectionStack* weights, Volume& x,
                          ProjectionStack& residual, const WlsOptions& o, const IterationCallback& on_iteration,
                          const Checkpointing* checkpointing, const StoppingRule& stopping) {
  o.validate();
  detail::require_problem_shapes("solve_wls_cg", A, b, x);
  if (weights && weights->data.size() != b.data.size())
    throw std::invalid_argument("solve_wls_cg: weights and line integrals differ in size");
  if (residual.data.size() != b.data.size())
    throw std::invalid_argument("solve_wls_cg: the residual and the line integrals differ in size");
  static const FloatBuffer unit;
  const FloatBuffer& w = weights ? weights->data : unit;
  auto start = std::chrono::steady_clock::now();
  // M^-1 (empty: no preconditioner, z = g). Recomputed on a resume: the same operator and weights
  // give the same diagonal.
  const bool preconditioned = o.preconditioner == CgPreconditioner::diagonal;
  const FloatBuffer inverse_M = preconditioned ? inverse_diagonal(A, weights, o) : FloatBuffer();
  const std::string solver_name = preconditioned ? "wls-cg-diagonal" : "wls-cg";

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
  double gz = 0, g0 = 0, g_norm = 0;  // g'M^-1 g, |g| at the start, the latest |g|
  int first = 1;
  if (resume) {
    check_solver_state(*resume, solver_name, {residual.data.size(), gradient.data.size(), direction.data.size()}, 2, x.layout);
    x.data = std::move(resume->x.data);
    residual.data = std::move(resume->vectors[0]);
    gradient.data = std::move(resume->vectors[1]);
    direction.data = std::move(resume->vectors[2]);
    gz = resume->scalars[0];
    g0 = resume->scalars[1];
    report.iterations = resume->log;
    first = resume->iteration + 1;
    g_norm = std::sqrt(A.sum_over_domain(dot(gradient.data, gradient.data)));
  } else {
    const double gg = A.sum_over_domain(dot(gradient.data, gradient.data));
    g0 = g_norm = std::sqrt(gg);
    gz = preconditioned ? A.sum_over_domain(detail::weighted_square_sum(gradient.data, inverse_M)) : gg;
    report.iterations.push_back(log_point(0, g0, g0));
    if (g0 == 0) {
      report.stop_reason = "zero gradient at the start (nothing to fit)";
      return report;
    }
    for (std::size_t i = 0; i < direction.data.size(); ++i)
      direction.data[i] = preconditioned ? -inverse_M[i] * gradient.data[i] : -gradient.data[i];
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
    const double alpha = gz / alpha_denominator;
    axpy(alpha, direction.data, x.data);
    axpy(alpha, Ad.data, residual.data);
    if (it == o.iterations && !o.gradient_after_last) {
      report.iterations.push_back(log_point(it, g_norm, g0));
      if (auto done = stopping ? stopping() : std::nullopt) report.stop_reason = std::move(*done);
      break;
    }
    detail::weighted_copy(Ad.data, w, scratch.data);
    A.apply_adjoint(scratch, H_direction);
    add_regulariser_normal(o.regulariser, o.lambda, direction, H_direction);
    axpy(alpha, H_direction.data, gradient.data);
    const double gg = A.sum_over_domain(dot(gradient.data, gradient.data));
    g_norm = std::sqrt(gg);
    const double gz_new = preconditioned ? A.sum_over_domain(detail::weighted_square_sum(gradient.data, inverse_M)) : gg;
    report.iterations.push_back(log_point(it, g_norm, g0));
    if (g_norm <= o.tolerance * g0) {
      report.stop_reason = "gradient fell below the tolerance after " + std::to_string(it) + " iterations";
      return report;
    }
    if (auto done = stopping ? stopping() : std::nullopt) {
      report.stop_reason = std::move(*done);
      return report;
    }
    const double beta = gz_new / gz;
    gz = gz_new;
    const std::ptrdiff_t n = static_cast<std::ptrdiff_t>(direction.data.size());
#pragma omp parallel for schedule(static)
    for (std::ptrdiff_t i = 0; i < n; ++i) {
      const std::size_t k = static_cast<std::size_t>(i);
      const double z = preconditioned ? double(inverse_M[k]) * gradient.data[k] : double(gradient.data[k]);
      direction.data[k] = static_cast<float>(-z + beta * direction.data[k]);
    }
    if (checkpointing) {
      const bool stop = checkpointing->stop_requested && checkpointing->stop_requested();
      if (stop || (checkpointing->every > 0 && it % checkpointing->every == 0 && it < o.iterations))
        checkpointing->save({solver_name, it, report.iterations, x, {&residual.data, &gradient.data, &direction.data}, {gz, g0}});
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

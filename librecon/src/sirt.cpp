#include "ctk/recon/sirt.hpp"

#include <algorithm>
#include <chrono>
#include <utility>

#include "ctk/core/error.hpp"
#include "vector_ops.hpp"

namespace ctk {

namespace {

void invert_nonzero(FloatBuffer& v) {
  for (float& x : v) x = x > 1e-12f ? 1.0f / x : 0.0f;
}

}  // namespace

void SirtOptions::validate() const {
  require_option(iterations >= 0, "SirtOptions.iterations", "at least 0", iterations);
  require_option(relaxation > 0 && relaxation < 2, "SirtOptions.relaxation", "a number in (0, 2)", relaxation);
}

SolverReport solve_sirt(const ProjectionOperator& A, const ProjectionStack& b, Volume& x, const SirtOptions& o,
                        const IterationCallback& on_iteration, const Checkpointing* checkpointing, const StoppingRule& stopping) {
  o.validate();
  detail::require_problem_shapes("solve_sirt", A, b, x);
  auto start = std::chrono::steady_clock::now();
  ProjectionStack row_weight(b.views, b.rows, b.cols), residual(b.views, b.rows, b.cols);
  Volume column_weight(x.layout), update(x.layout);
  {
    Volume ones(x.layout);
    std::fill(ones.data.begin(), ones.data.end(), 1.0f);
    A.apply(ones, row_weight);
    std::fill(residual.data.begin(), residual.data.end(), 1.0f);
    A.apply_adjoint(residual, column_weight);
  }
  invert_nonzero(row_weight.data);
  invert_nonzero(column_weight.data);

  SolverReport report;
  int first = 0;
  if (checkpointing && checkpointing->resume) {
    check_solver_state(*checkpointing->resume, "sirt", {}, 0, x.layout);
    x.data = std::move(checkpointing->resume->x.data);
    report.iterations = checkpointing->resume->log;
    first = checkpointing->resume->iteration;
  }
  const std::ptrdiff_t n_rays = static_cast<std::ptrdiff_t>(b.data.size());
  const std::ptrdiff_t n_voxels = static_cast<std::ptrdiff_t>(x.data.size());
  for (int it = first; it <= o.iterations; ++it) {
    A.apply(x, residual);  // residual = b - A x
#pragma omp parallel for schedule(static)
    for (std::ptrdiff_t i = 0; i < n_rays; ++i) {
      const std::size_t k = static_cast<std::size_t>(i);
      residual.data[k] = b.data[k] - residual.data[k];
    }
    IterationLog log;
    log.iteration = it;
    log.data_term = 0.5 * A.sum_over_range(detail::weighted_square_sum(residual.data, {}));
    log.cost = log.data_term;
    log.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    start = std::chrono::steady_clock::now();
    report.iterations.push_back(log);
    if (on_iteration) on_iteration(log);
    if (auto done = stopping ? stopping() : std::nullopt) {
      report.stop_reason = std::move(*done);
      return report;
    }
    if (it == o.iterations) break;
#pragma omp parallel for schedule(static)
    for (std::ptrdiff_t i = 0; i < n_rays; ++i)
      residual.data[static_cast<std::size_t>(i)] *= row_weight.data[static_cast<std::size_t>(i)];
    A.apply_adjoint(residual, update);
    const float relax = static_cast<float>(o.relaxation);
#pragma omp parallel for schedule(static)
    for (std::ptrdiff_t i = 0; i < n_voxels; ++i) {
      const std::size_t k = static_cast<std::size_t>(i);
      float v = x.data[k] + relax * column_weight.data[k] * update.data[k];
      x.data[k] = o.non_negative ? std::max(v, 0.0f) : v;
    }
    if (checkpointing) {  // it + 1 updates done
      const bool stop = checkpointing->stop_requested && checkpointing->stop_requested();
      if (stop || (checkpointing->every > 0 && (it + 1) % checkpointing->every == 0 && it + 1 < o.iterations))
        checkpointing->save({"sirt", it + 1, report.iterations, x, {}, {}});
      if (stop) {
        report.stop_reason = kStoppedOnRequest;
        return report;
      }
    }
  }
  report.stop_reason = "iteration limit (" + std::to_string(o.iterations) + ") reached";
  return report;
}

}  // namespace ctk

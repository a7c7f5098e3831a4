#pragma once
// Threaded reductions and updates on float arrays, accumulating in double (solver internals).
#include <algorithm>
#include <cstddef>
#include <stdexcept>
#include <string>
#include <vector>

#include "ctk/core/float_buffer.hpp"
#include "ctk/proj/projection_operator.hpp"

namespace ctk::detail {

/// Throws std::invalid_argument, naming the solver, when b is not of A's range or x not of its domain.
inline void require_problem_shapes(const char* solver, const ProjectionOperator& A, const ProjectionStack& b, const Volume& x) {
  const StackShape r = A.range();
  if (!(StackShape::of(b) == r))
    throw std::invalid_argument(std::string(solver) + ": the line integrals are " + std::to_string(b.views) + " x " +
                                std::to_string(b.rows) + " x " + std::to_string(b.cols) + " but the operator projects to " +
                                std::to_string(r.views) + " x " + std::to_string(r.rows) + " x " + std::to_string(r.cols));
  if (!(x.layout == A.domain()))
    throw std::invalid_argument(std::string(solver) + ": the volume's layout is not the operator's domain");
}

inline double dot(const FloatBuffer& a, const FloatBuffer& b) {
  double sum = 0;
  const std::ptrdiff_t n = static_cast<std::ptrdiff_t>(a.size());
#pragma omp parallel for reduction(+ : sum) schedule(static)
  for (std::ptrdiff_t i = 0; i < n; ++i) sum += double(a[static_cast<std::size_t>(i)]) * double(b[static_cast<std::size_t>(i)]);
  return sum;
}

/// sum_i w_i a_i^2 (w empty: unit weights).
inline double weighted_square_sum(const FloatBuffer& a, const FloatBuffer& w) {
  double sum = 0;
  const std::ptrdiff_t n = static_cast<std::ptrdiff_t>(a.size());
  const bool weighted = !w.empty();
#pragma omp parallel for reduction(+ : sum) schedule(static)
  for (std::ptrdiff_t i = 0; i < n; ++i) {
    const double x = a[static_cast<std::size_t>(i)];
    sum += (weighted ? double(w[static_cast<std::size_t>(i)]) : 1.0) * x * x;
  }
  return sum;
}

/// y += alpha * x
inline void axpy(double alpha, const FloatBuffer& x, FloatBuffer& y) {
  const std::ptrdiff_t n = static_cast<std::ptrdiff_t>(x.size());
  const float a = static_cast<float>(alpha);
#pragma omp parallel for schedule(static)
  for (std::ptrdiff_t i = 0; i < n; ++i) y[static_cast<std::size_t>(i)] += a * x[static_cast<std::size_t>(i)];
}

/// out = scale * w * x elementwise (w empty: scale * x; a scale of 1 changes no bit).
inline void weighted_copy(const FloatBuffer& x, const FloatBuffer& w, FloatBuffer& out, float scale = 1) {
  const std::ptrdiff_t n = static_cast<std::ptrdiff_t>(x.size());
  out.resize(x.size());
  const bool weighted = !w.empty();
#pragma omp parallel for schedule(static)
  for (std::ptrdiff_t i = 0; i < n; ++i) {
    const std::size_t k = static_cast<std::size_t>(i);
    out[k] = scale * (weighted ? w[k] * x[k] : x[k]);
  }
}

/// Views `views` of `all`, in that order, into `out` (reshaped; shrinking keeps the allocation).
inline void gather_views(const ProjectionStack& all, const std::vector<int>& views, ProjectionStack& out) {
  const std::size_t pixels = static_cast<std::size_t>(all.rows) * static_cast<std::size_t>(all.cols);
  out.views = static_cast<int>(views.size());
  out.rows = all.rows;
  out.cols = all.cols;
  out.data.resize(static_cast<std::size_t>(out.views) * pixels);
  const std::ptrdiff_t n = static_cast<std::ptrdiff_t>(views.size());
#pragma omp parallel for schedule(static)
  for (std::ptrdiff_t k = 0; k < n; ++k)
    std::copy_n(all.data.data() + static_cast<std::size_t>(views[static_cast<std::size_t>(k)]) * pixels, pixels,
                out.data.data() + static_cast<std::size_t>(k) * pixels);
}

}  // namespace ctk::detail

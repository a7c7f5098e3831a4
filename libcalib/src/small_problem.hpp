#pragma once
// Solver settings for the many small fits of libcalib (a pose, a sphere's profile): a handful of
// unknowns, dense normal equations (sparse machinery and QR only cost at this size), one thread (callers run views in
// parallel), silent.
#include <ceres/ceres.h>

namespace ctk {

inline ceres::Solver::Summary solve_small_problem(ceres::Problem& problem, int max_iterations, double tolerance = 1e-6) {
  ceres::Solver::Options options;
  options.max_num_iterations = max_iterations;
  options.linear_solver_type = ceres::DENSE_NORMAL_CHOLESKY;
  options.function_tolerance = tolerance;
  options.parameter_tolerance = tolerance * 1e-2;
  options.logging_type = ceres::SILENT;
  options.num_threads = 1;
  ceres::Solver::Summary summary;
  ceres::Solve(options, &problem, &summary);
  return summary;
}

}  // namespace ctk

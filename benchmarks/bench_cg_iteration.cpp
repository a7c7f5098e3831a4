// Google Benchmark: one conjugate-gradient iteration of the WLS solver (one forward and one back
// projection plus the vector updates) on the standard problem, circular and spherical.
// Arguments: {scale, views}; scale 1 is 256^3 voxels, 360 views of 256^2.
#include <benchmark/benchmark.h>

#include "ctk/proj/joseph_operator.hpp"
#include "ctk/proj/standard_problem.hpp"
#include "ctk/recon/wls_cg.hpp"

namespace ctk {
namespace {

template <StandardTrajectory T>
void BM_CgIteration(benchmark::State& state) {
  const StandardProblem p = standard_problem(T, static_cast<int>(state.range(1)), static_cast<int>(state.range(0)));
  ProjectionStack b(static_cast<int>(p.views.size()), p.rows, p.cols);
  std::fill(b.data.begin(), b.data.end(), 1.0f);
  const JosephOperator A(p.views, p.layout, p.rows, p.cols);
  WlsOptions o;
  o.iterations = 1;
  o.tolerance = 0;
  for (auto _ : state) {
    Volume x(p.layout);
    const SolverReport r = solve_wls_cg(A, b, nullptr, x, o);
    // Time only iteration 1 (the start-up back projection is paid once per solve).
    state.SetIterationTime(r.iterations.at(1).seconds);
  }
  state.counters["views"] = static_cast<double>(p.views.size());
}

BENCHMARK(BM_CgIteration<StandardTrajectory::circular>)->Args({1, 360})->UseManualTime()->Iterations(1)->Unit(benchmark::kSecond);
BENCHMARK(BM_CgIteration<StandardTrajectory::spherical>)
    ->Args({1, 360})
    ->UseManualTime()
    ->Iterations(1)
    ->Unit(benchmark::kSecond);

}  // namespace
}  // namespace ctk

BENCHMARK_MAIN();

// Google Benchmark of the Joseph projectors and of FDK's voxel-driven back projection on the
// standard problem (ctk/proj/standard_problem.hpp).
// Arguments: {scale, views}; scale 1 is the standard problem (256^3, 256^2, 360 views). The
// reference runs on one thread, the fast projector on all; compare their voxel_views/s counters.
#include <benchmark/benchmark.h>

#include "ctk/proj/joseph_projector.hpp"
#include "ctk/proj/reference_projector.hpp"
#include "ctk/proj/standard_problem.hpp"
#include "ctk/proj/voxel_backprojection.hpp"

namespace ctk {
namespace {

struct Fixture {
  StandardProblem problem;
  Volume x;
  ProjectionStack y;
  Fixture(StandardTrajectory t, int scale, int views)
      : problem(standard_problem(t, views, scale)), x(problem.layout), y(views, problem.rows, problem.cols) {
    std::fill(x.data.begin(), x.data.end(), 1.0f);
    std::fill(y.data.begin(), y.data.end(), 1.0f);
  }
  void count(benchmark::State& state) const {
    state.counters["voxel_views_per_s"] =
        benchmark::Counter(static_cast<double>(problem.layout.voxel_count()) * static_cast<double>(problem.views.size()),
                           benchmark::Counter::kIsIterationInvariantRate);
  }
};

// One benchmark body for all four: `project` runs one projection of the fixture.
template <StandardTrajectory T, typename Project>
void run(benchmark::State& state, Project project) {
  Fixture f(T, static_cast<int>(state.range(0)), static_cast<int>(state.range(1)));
  for (auto _ : state) project(f);
  f.count(state);
}

template <StandardTrajectory T>
void BM_FastForward(benchmark::State& state) {
  run<T>(state, [](Fixture& f) { JosephProjector().forward(f.x, f.problem.views, f.y); });
}
template <StandardTrajectory T>
void BM_FastBack(benchmark::State& state) {
  run<T>(state, [](Fixture& f) { JosephProjector().back(f.y, f.problem.views, f.x); });
}
template <StandardTrajectory T>
void BM_ReferenceForward(benchmark::State& state) {
  run<T>(state, [](Fixture& f) { forward_project_reference(f.x, f.problem.views, f.y); });
}
template <StandardTrajectory T>
void BM_ReferenceBack(benchmark::State& state) {
  run<T>(state, [](Fixture& f) { back_project_reference(f.y, f.problem.views, f.x); });
}

// FDK's back projection (circular scans only), weighted by (1000 mm / depth)^2.
void BM_FastVoxelBack(benchmark::State& state) {
  run<StandardTrajectory::circular>(state, [](Fixture& f) { voxel_backproject(f.y, f.problem.views, 1000.0, f.x); });
}
void BM_ReferenceVoxelBack(benchmark::State& state) {
  run<StandardTrajectory::circular>(state, [](Fixture& f) { voxel_backproject_reference(f.y, f.problem.views, 1000.0, f.x); });
}

// The fast projector on the full standard problem; the reference on 12 of its views (same
// volume and detector), which its voxel_views_per_s counter makes comparable.
constexpr auto kCircular = StandardTrajectory::circular;
constexpr auto kSpherical = StandardTrajectory::spherical;
BENCHMARK(BM_FastForward<kCircular>)->Args({1, 360})->Unit(benchmark::kSecond)->UseRealTime();
BENCHMARK(BM_FastBack<kCircular>)->Args({1, 360})->Unit(benchmark::kSecond)->UseRealTime();
BENCHMARK(BM_ReferenceForward<kCircular>)->Args({1, 12})->Unit(benchmark::kSecond)->UseRealTime();
BENCHMARK(BM_ReferenceBack<kCircular>)->Args({1, 12})->Unit(benchmark::kSecond)->UseRealTime();
BENCHMARK(BM_FastForward<kSpherical>)->Args({1, 360})->Unit(benchmark::kSecond)->UseRealTime();
BENCHMARK(BM_FastBack<kSpherical>)->Args({1, 360})->Unit(benchmark::kSecond)->UseRealTime();
BENCHMARK(BM_ReferenceForward<kSpherical>)->Args({1, 12})->Unit(benchmark::kSecond)->UseRealTime();
BENCHMARK(BM_ReferenceBack<kSpherical>)->Args({1, 12})->Unit(benchmark::kSecond)->UseRealTime();
BENCHMARK(BM_FastVoxelBack)->Args({1, 360})->Unit(benchmark::kSecond)->UseRealTime();
BENCHMARK(BM_ReferenceVoxelBack)->Args({1, 12})->Unit(benchmark::kSecond)->UseRealTime();

}  // namespace
}  // namespace ctk

BENCHMARK_MAIN();

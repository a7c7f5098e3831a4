// Google Benchmark: one planning iteration at a 128^3 coarse volume on all cores.
//  BM_PlanningStep/<views>: the planner's own work in the real loop (calibrating the new view at
//    720 x 720, the warm-started reconstruction update, segmentation, scoring 768 candidate
//    directions, the draw), measured over a whole simulated run of thesis sample 1
//    (polychromatic, robot noise) with `views` views; the counters give the mean and the worst
//    step. The simulator's rendering (the robot's move and exposure) is not counted.
//  BM_PictureMedian/<boxed>: the 3^3 median the planner reads its 128^3 picture through, over
//    the whole volume (0) or over the box a reading looks at (1, the planner's own).
#include <benchmark/benchmark.h>

#include <algorithm>

#include "ctk/phantoms/builtin_phantoms.hpp"
#include "ctk/plan/picture_median.hpp"
#include "ctk/plan/plan_trajectory.hpp"
#include "ctk/plan/simulated_acquisition.hpp"

namespace ctk {
namespace {

PlanningOptions default_planning(int views) {
  PlanningOptions o;
  o.views = views;
  o.coarse_volume = VolumeLayout::centred({128, 128, 128}, Eigen::Vector3d::Constant(0.75));
  o.planner.planned_views = views;
  o.planner.damage_floor_mm = 1.5;
  return o;
}

void BM_PlanningStep(benchmark::State& state) {
  const int views = static_cast<int>(state.range(0));
  ScanSimulation sim;
  sim.setup = reference_panda_setup(Detector{720, 720, 0.6, 0.6}, 2150, 1360);
  sim.holder = reference_helix_holder();
  sim.sample = builtin_phantom("sample-1");
  sim.spectrum = tube_spectrum(90, 2.0);
  const PlanningSetup setup = planning_setup(sim);
  for (auto _ : state) {
    SimulatedLab lab(sim);
    SimulatedAcquisition side(lab);
    const PlanningResult r = plan_trajectory(side, setup, default_planning(views));
    double sum = 0, worst = 0;
    for (double s : r.step_seconds) {
      sum += s;
      worst = std::max(worst, s);
    }
    const double mean = sum / static_cast<double>(std::max<std::size_t>(1, r.step_seconds.size()));
    state.SetIterationTime(mean);
    state.counters["mean_step_s"] = mean;
    state.counters["max_step_s"] = worst;
    state.counters["planned_steps"] = static_cast<double>(r.step_seconds.size());
  }
}

BENCHMARK(BM_PlanningStep)->Arg(100)->UseManualTime()->Iterations(1)->Unit(benchmark::kSecond);

void BM_PictureMedian(benchmark::State& state) {
  Volume picture(VolumeLayout::centred({128, 128, 128}, Eigen::Vector3d::Constant(0.75)));
  for (std::size_t v = 0; v < picture.data.size(); ++v) picture.data[v] = static_cast<float>((v * 2654435761U) % 1000) * 1e-4f;
  // The box of the planner's reading (sample region and holder wall, 28 mm about the axis, 45 mm
  // along it, one voxel more): 78 x 78 x 124 of the 128^3 voxels.
  const VoxelBox box{{25, 25, 2}, {103, 103, 126}};
  for (auto _ : state) benchmark::DoNotOptimize(state.range(0) ? median_3x3x3(picture, box) : median_3x3x3(picture));
}

BENCHMARK(BM_PictureMedian)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace ctk

BENCHMARK_MAIN();

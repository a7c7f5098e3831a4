// Google Benchmark: one planning iteration at a 128^3 coarse volume on all cores.
//  BM_PlanningStep/<views>: the planner's own work in the real loop (calibrating the new view at
//    720 x 720, the warm-started reconstruction update, segmentation, scoring 768 candidate
//    directions, the draw), measured over a whole simulated run of thesis sample 1
//    (polychromatic, robot noise) with `views` views; the counters give the mean and the worst
//    step. The simulator's rendering (the robot's move and exposure) is not counted.
#include <benchmark/benchmark.h>

#include <algorithm>

#include "ctk/phantoms/builtin_phantoms.hpp"
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

}  // namespace
}  // namespace ctk

BENCHMARK_MAIN();

// The planning workflows end to end: the simulated lab's run writes a planned scan another lab can
// take as its setup, and lab mode plans through request/answer files with a lab process (here a
// thread driving the simulated lab), writes the planned scan to its own folder and leaves
// everything the lab wrote as it was.
#include <gtest/gtest.h>

#include <chrono>
#include <fstream>
#include <map>
#include <sstream>
#include <thread>

#include "../test_support.hpp"
#include "ctk/core/error.hpp"
#include "ctk/geom/geometry_file.hpp"
#include "ctk/geom/scan.hpp"
#include "ctk/phantoms/builtin_phantoms.hpp"
#include "ctk/plan/simulated_acquisition.hpp"
#include "ctk/plan/simulated_planning_run.hpp"

namespace ctk {
namespace {

namespace fs = std::filesystem;

std::string contents(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

// A small planner: 6 scout directions, a 32^3 coarse volume of 3 mm voxels, the detector binned 2.
PlanRequest small_plan(int views) {
  PlanRequest p;
  p.views = views;
  p.scout_nside = 1;
  p.coarse_size = 32;
  p.coarse_voxel_mm = 3;
  p.binning = 2;
  return p;
}

SimulatedPlanRequest small_simulation(const fs::path& out, int views) {
  SimulatedPlanRequest r;
  r.plan = small_plan(views);
  r.phantoms = {"sample-2"};
  r.out = out;
  r.cols = r.rows = 360;
  r.pitch_mm = 1.2;
  return r;
}

TEST(PlanningRun, SimulatedThenLabModeThroughFiles) {
  const fs::path dir = testing::scratch_dir();
  // The simulated run: a planned trajectory of 2 views, whose scan serves as the lab's setup.
  const SimulatedPlanRequest simulated = small_simulation(dir / "simulated", 2);
  const SimulatedPlanningRun first = run_simulated_planning(simulated);
  ASSERT_EQ(first.trajectories.size(), 1u);
  EXPECT_FALSE(first.comparison);
  EXPECT_EQ(first.trajectories[0].result.calibrated(), 2);
  EXPECT_EQ(first.trajectories[0].report()["format"], "ctk-plan/1");
  EXPECT_NE(first.brief().find("2 views calibrated"), std::string::npos) << first.brief();
  const fs::path setup = dir / "simulated" / "planned" / "scan.json";
  for (const char* name : {"scan.json", "geometry.json", "trajectory.json", "plan-map.png", "coarse.nrrd"})
    EXPECT_TRUE(fs::exists(dir / "simulated" / "planned" / name)) << name;

  LabPlanRequest request;
  request.plan = small_plan(5);
  request.lab = dir / "lab";
  request.setup = setup;
  request.out = dir / "lab";  // the lab's own folder: refused before anything is asked or written
  request.timeout_s = 60;
  fs::create_directories(request.lab);
  try {
    run_lab_planning(request);
    FAIL() << "an output inside the lab's folder was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("out: "), std::string::npos) << e.what();
  }
  EXPECT_TRUE(fs::is_empty(request.lab));

  // The lab: answers every request with a shot of the simulated lab, until the planner is done.
  request.out = dir / "planned";
  ScanSimulation same_world = simulated_world(simulated);
  same_world.seed = 7;  // another robot and photon noise than the run that wrote the setup
  SimulatedLab world(same_world);
  SimulatedAcquisition shots(world, request.lab);
  std::map<fs::path, std::string> written;  // what the lab wrote, to check nothing was touched
  std::thread lab([&] {
    for (int view = 0;; ++view) {
      const fs::path asked = request_file(request.lab, view);
      const auto give_up = std::chrono::steady_clock::now() + std::chrono::seconds(120);
      while (!fs::exists(asked) && !fs::exists(request.lab / "done.json") && std::chrono::steady_clock::now() < give_up)
        std::this_thread::sleep_for(std::chrono::milliseconds(5));
      if (!fs::exists(asked)) return;
      const AcquisitionAnswer a = shots.acquire(read_request(asked));
      write_answer(request.lab, view, a);
      written[answer_file(request.lab, view)] = contents(answer_file(request.lab, view));
      if (a.acquired) written[request.lab / a.projection_file] = contents(request.lab / a.projection_file);
    }
  });
  int seen = 0;
  PlanningRun run;
  try {
    run = run_lab_planning(request, [&](const PlannedViewRecord&) { ++seen; });
  } catch (...) {
    lab.join();
    throw;
  }
  lab.join();
  EXPECT_EQ(seen, static_cast<int>(run.result.views.size()));
  ASSERT_EQ(run.result.calibrated(), 5);
  EXPECT_TRUE(fs::exists(request.lab / "done.json"));
  for (const auto& [file, text] : written) EXPECT_EQ(contents(file), text) << file;

  // The planned scan names the lab's images from its own folder, and its calibrated matrices put
  // points of the holder where the true ones do.
  const ScanDescription scan = read_scan(request.out / "scan.json");
  const Geometry geometry = read_geometry(request.out / "geometry.json");
  ASSERT_EQ(scan.projections.count, run.result.acquired());
  EXPECT_EQ(geometry.ok_views().size(), 5u);
  int checked = 0;
  for (const PlannedViewRecord& v : run.result.views) {
    if (!v.calibrated) continue;
    const fs::path image = scan.resolve(v.projection_file);
    EXPECT_TRUE(fs::equivalent(image, request.lab / "projections" / fs::path(v.projection_file).filename())) << image;
    const ProjectionMatrix& truth = shots.true_matrices().at(v.index);
    for (const Eigen::Vector3d& X : {Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(20, 0, 30), Eigen::Vector3d(0, -20, -30)})
      EXPECT_LT((v.P->project(X) - truth.project(X)).norm(), 0.5) << "request " << v.index;
    ++checked;
  }
  EXPECT_EQ(checked, 5);
  EXPECT_EQ(run.report()["calibrated"], 5);
  EXPECT_TRUE(fs::exists(request.out / "plan-map.png"));
}

// Comparing needs the trajectories: compare_only on a folder without them names the missing one.
TEST(PlanningRun, CompareOnlyNamesTheMissingTrajectory) {
  const fs::path dir = testing::scratch_dir();
  SimulatedPlanRequest r = small_simulation(dir, 4);
  r.compare_only = true;
  try {
    run_simulated_planning(r);
    FAIL() << "compared trajectories that are not there";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("planned"), std::string::npos) << e.what();
  }
  EXPECT_FALSE(fs::exists(dir / "comparison.json"));
}

}  // namespace
}  // namespace ctk

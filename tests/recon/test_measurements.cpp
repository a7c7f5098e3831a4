// Loading a scan for reconstruction: only "ok" views are read (a rejected view's image is never
// opened), counts scans get weights, line-integral scans come through unchanged.
#include <gtest/gtest.h>

#include "../test_support.hpp"
#include "ctk/geom/error.hpp"
#include "ctk/phantoms/builtin_phantoms.hpp"
#include "ctk/phantoms/scan_simulation.hpp"
#include "ctk/recon/measurements.hpp"

namespace ctk {
namespace {

ScanSimulation tiny_scan(SimulatedOutput output) {
  ScanSimulation sim;
  sim.setup = reference_panda_setup({48, 40, 9.0, 9.0}, 2150, 1360);
  sim.holder = reference_helix_holder();
  sim.trajectory = circular_robot_trajectory(sim.setup, 6);
  sim.output = output;
  return sim;
}

TEST(Measurements, RejectedViewsAreNeverRead) {
  const auto dir = testing::scratch_dir();
  simulate_scan(tiny_scan(SimulatedOutput::line_integrals), dir);
  const ScanDescription scan = read_scan(dir / "scan.json");
  Geometry g = read_geometry(dir / "truth-geometry.json");
  g.views[2].status = ViewStatus::rejected;
  g.views[2].reason = "residual above threshold";
  testing::write_text(scan.projection_path(2), "not an image");
  const Measurements m = load_measurements(scan, g);
  EXPECT_EQ(m.view_indices, (std::vector<int>{0, 1, 3, 4, 5}));
  EXPECT_EQ(m.line_integrals.views, 5);
  EXPECT_EQ(m.weights.views, 0);  // line integrals: unit weights
  const Image view3 = read_image(scan.projection_path(3));
  EXPECT_TRUE(std::equal(view3.pixels.begin(), view3.pixels.end(), m.line_integrals.view(2)));
  // The same damaged image in an ok view is an error naming the file.
  g.views[2].status = ViewStatus::ok;
  try {
    load_measurements(scan, g);
    FAIL() << "expected an InputError";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("proj_0002"), std::string::npos) << e.what();
  }
}

// A geometry that does not fit the scan (another scan's, or another binning) is refused with
// the geometry file and its key named, as every bad input is.
TEST(Measurements, AGeometryForAnotherDetectorNamesItsFileAndKey) {
  const auto dir = testing::scratch_dir();
  simulate_scan(tiny_scan(SimulatedOutput::line_integrals), dir);
  const ScanDescription scan = read_scan(dir / "scan.json");
  const auto file = dir / "truth-geometry.json";
  const auto expect_refused = [&](const Geometry& g, const std::string& key) {
    try {
      load_measurements(scan, g);
      FAIL() << "expected an InputError naming " << key;
    } catch (const InputError& e) {
      EXPECT_EQ(e.file(), file.string()) << e.what();
      EXPECT_EQ(e.where(), "key '" + key + "'") << e.what();
    }
  };
  Geometry g = read_geometry(file);
  g.detector.cols = scan.detector.cols / 2;
  expect_refused(g, "detector");
  g = read_geometry(file);
  g.views[4].index = scan.projections.count;
  expect_refused(g, "views[4].index");
}

TEST(Measurements, CountsGiveLineIntegralsNearTheTruthAndWeights) {
  const auto dir = testing::scratch_dir();
  ScanSimulation sim = tiny_scan(SimulatedOutput::counts);
  sim.counts = {60000, 100};
  simulate_scan(sim, dir);
  const ScanDescription scan = read_scan(dir / "scan.json");
  const Measurements m = load_measurements(scan, read_geometry(dir / "truth-geometry.json"));
  ASSERT_EQ(m.weights.views, 6);
  // Open beam: line integral ~ 0 within noise (sigma ~ 1/sqrt(60000)), weight ~ 1.
  EXPECT_NEAR(m.line_integrals.at(0, 0, 0), 0.0, 0.03);
  EXPECT_NEAR(m.weights.at(0, 0, 0), 1.0, 0.03);
  EXPECT_EQ(m.clamped_pixels, 0u);
}

}  // namespace
}  // namespace ctk

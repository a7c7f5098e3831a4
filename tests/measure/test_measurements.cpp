// Loading a scan for reconstruction: only "ok" views are read (a rejected view's image is never
// opened), counts scans get weights, line-integral scans come through unchanged.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>

#include "../test_support.hpp"
#include "ctk/core/error.hpp"
#include "ctk/measure/measurements.hpp"
#include "ctk/measure/projection_reading.hpp"
#include "ctk/phantoms/builtin_phantoms.hpp"
#include "ctk/phantoms/scan_simulation.hpp"

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

// A tiny counts scan of 60000 counts above a dark of 100, simulated into `dir`.
ScanDescription counts_scan(const std::filesystem::path& dir) {
  ScanSimulation sim = tiny_scan(SimulatedOutput::counts);
  sim.counts = {60000, 100};
  simulate_scan(sim, dir);
  return read_scan(dir / "scan.json");
}

TEST(Measurements, CountsGiveLineIntegralsNearTheTruthAndWeights) {
  const auto dir = testing::scratch_dir();
  const ScanDescription scan = counts_scan(dir);
  const Measurements m = load_measurements(scan, read_geometry(dir / "truth-geometry.json"));
  ASSERT_EQ(m.weights.views, 6);
  // Open beam: line integral ~ 0 within noise (sigma ~ 1/sqrt(60000)), weight ~ 1.
  EXPECT_NEAR(m.line_integrals.at(0, 0, 0), 0.0, 0.03);
  EXPECT_NEAR(m.weights.at(0, 0, 0), 1.0, 0.03);
  EXPECT_EQ(m.clamped_pixels, 0u);
}

// One infinite count (a saturated or overflowed pixel written as +Inf) is masked and counted like a
// NaN: its weight is zero and every weight finite (weight +Inf gave an all-zero WLS-CG volume).
TEST(Measurements, AnInfiniteCountIsMaskedAndCounted) {
  const auto dir = testing::scratch_dir();
  const ScanDescription scan = counts_scan(dir);
  Image view = read_image(scan.projection_path(2));
  const auto at = static_cast<std::size_t>(7 * view.cols + 9);
  view.pixels[at] = std::numeric_limits<float>::infinity();
  write_image_float(view, scan.projection_path(2));
  const Measurements m = load_measurements(scan, read_geometry(dir / "truth-geometry.json"));
  EXPECT_EQ(m.masked_pixels, 1u);
  EXPECT_EQ(m.clamped_pixels, 0u);
  EXPECT_EQ(m.weights.at(2, 7, 9), 0.0f);
  for (std::size_t i = 0; i < m.weights.data.size(); ++i) ASSERT_TRUE(std::isfinite(m.weights.data[i])) << i;
  for (std::size_t i = 0; i < m.line_integrals.data.size(); ++i) ASSERT_TRUE(std::isfinite(m.line_integrals.data[i])) << i;
}

// A binned counts scan: each binned pixel is the line integral of the counts its pixels collected
// together, -log(sum(I - dark) / sum(flat - dark)), not the mean of their line integrals.
TEST(Measurements, BinnedCountsAreSummedBeforeTheLogarithm) {
  const auto dir = testing::scratch_dir();
  const ScanDescription scan = counts_scan(dir);
  ScanDescription binned = scan;
  bin_scan(binned, 2);
  const Image counts = read_image(scan.projection_path(3)), flat = read_image(scan.resolve(scan.projections.flat[0])),
              dark = read_image(scan.resolve(scan.projections.dark[0]));
  const Image p = read_line_integrals(binned, 3, read_flat_dark(binned));
  ASSERT_EQ(p.cols, 24);
  ASSERT_EQ(p.rows, 20);
  double worst = 0, unlike_mean_of_logs = 0;
  for (int r = 0; r < p.rows; ++r)
    for (int c = 0; c < p.cols; ++c) {
      double detected = 0, open = 0, mean_of_logs = 0;
      for (int dr = 0; dr < 2; ++dr)
        for (int dc = 0; dc < 2; ++dc) {
          const std::size_t i = static_cast<std::size_t>((2 * r + dr) * counts.cols + 2 * c + dc);
          detected += counts.pixels[i] - dark.pixels[i];
          open += flat.pixels[i] - dark.pixels[i];
          mean_of_logs -= 0.25 * std::log((counts.pixels[i] - dark.pixels[i]) / (flat.pixels[i] - dark.pixels[i]));
        }
      const double expected = -std::log(detected / open);
      unlike_mean_of_logs = std::max(unlike_mean_of_logs, std::abs(mean_of_logs - expected));
      worst = std::max(worst, std::abs(p.pixels[static_cast<std::size_t>(r * p.cols + c)] - expected));
    }
  EXPECT_GT(unlike_mean_of_logs, 1e-4);  // the shadows' edges tell the two apart
  EXPECT_LT(worst, 1e-5);
}

// The conversion runs as SIMD lanes and a scalar tail: every lane and the tail follow the
// definition, -log(max(I - dark, 0.5) / (flat - dark)) with the transmission clamped to
// (0.5 / open, 1.5] where implausible, weights the unclamped transmission; a count that is not
// finite (NaN, +Inf, -Inf) gives NaN, neither clamped nor weighted, for mask_non_finite to mask and
// count (a +Inf count clamped to the flat had weight +Inf: an all-zero WLS-CG volume).
TEST(Measurements, CountsToLineIntegralsFollowTheDefinitionInEveryLane) {
  const int n = 1003;  // not a multiple of any vector width
  Image counts{n, 1, std::vector<float>(n)}, flat{n, 1, std::vector<float>(n)}, dark{n, 1, std::vector<float>(n)};
  std::uint32_t state = 12345;
  auto next = [&] { return (state = state * 1664525u + 1013904223u) >> 8; };
  for (int i = 0; i < n; ++i) {
    const auto u = static_cast<std::size_t>(i);
    dark.pixels[u] = static_cast<float>(90 + next() % 20);
    flat.pixels[u] = static_cast<float>(i % 97 == 0 ? 50 + next() % 80 : 8000 + next() % 4000);  // some flats at or below dark
    const std::uint32_t kind = next() % 12;
    counts.pixels[u] = kind == 0   ? dark.pixels[u] - 5                       // below dark
                       : kind == 1 ? flat.pixels[u] * 2                       // transmission above 1.5
                       : kind == 2 ? std::numeric_limits<float>::quiet_NaN()  // a dead pixel
                       : kind == 3 ? std::numeric_limits<float>::infinity()   // an overflow
                       : kind == 4 ? -std::numeric_limits<float>::infinity()
                                   : dark.pixels[u] + static_cast<float>(next() % 9000);
  }
  std::vector<float> p(n), w(n);
  std::size_t clamped = 0;
  counts_to_line_integrals(counts, flat, dark, p.data(), w.data(), clamped);
  std::size_t expected_clamped = 0;
  for (int i = 0; i < n; ++i) {
    const auto u = static_cast<std::size_t>(i);
    const double open = double(flat.pixels[u]) - dark.pixels[u], detected = double(counts.pixels[u]) - dark.pixels[u];
    if (!std::isfinite(counts.pixels[u])) {
      EXPECT_TRUE(std::isnan(p[u])) << i << ": count " << counts.pixels[u];
      continue;
    }
    double t = open > 0 ? std::max(detected, 0.5) / open : 1.5;
    if (open <= 0 || detected < 0.5 || t > 1.5) {
      ++expected_clamped;
      t = std::clamp(t, 0.5 / std::max(open, 1.0), 1.5);
    }
    EXPECT_NEAR(p[u], -std::log(t), 2e-6 * std::max(1.0, std::abs(std::log(t)))) << i;
    EXPECT_NEAR(w[u], open > 0 ? std::max(detected, 0.5) / open : 0.0, 1e-6 * std::max(1.0, double(std::abs(w[u])))) << i;
  }
  EXPECT_EQ(clamped, expected_clamped);
}

// A view described twice, or a matrix that puts the volume behind the source (an all-zero volume
// before), is refused naming the geometry file and key.
TEST(Measurements, DuplicateViewsAndMatricesBehindTheSourceAreRefused) {
  const auto dir = testing::scratch_dir();
  simulate_scan(tiny_scan(SimulatedOutput::line_integrals), dir);
  const ScanDescription scan = read_scan(dir / "scan.json");
  const Geometry good = read_geometry(dir / "truth-geometry.json");
  auto refused = [&](const Geometry& g, const std::string& key) {
    try {
      load_measurements(scan, g);
      ADD_FAILURE() << "accepted; expected an error naming " << key;
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(key), std::string::npos) << e.what();
    }
  };
  Geometry twice = good;
  twice.views[3].index = 1;
  refused(twice, "key 'views[3].index'");
  Geometry behind = good;
  behind.views[2].P = ProjectionMatrix(-behind.views[2].P->matrix());
  refused(behind, "key 'views[2].P'");
}

// Non-finite pixels (a dead pixel written as NaN, an overflow as inf) are masked with their
// neighbours' mean and counted; a view with more of them than kMostMaskedFraction is left out
// with the reason. Nothing that reaches a solver is anything but a finite number.
TEST(Measurements, NonFinitePixelsAreMaskedAndAViewFullOfThemIsLeftOut) {
  const auto dir = testing::scratch_dir();
  simulate_scan(tiny_scan(SimulatedOutput::line_integrals), dir);
  const ScanDescription scan = read_scan(dir / "scan.json");
  Image few = read_image(scan.projection_path(1));
  const Image clean = few;
  const int cols = few.cols;
  few.pixels[static_cast<std::size_t>(10 * cols + 20)] = std::numeric_limits<float>::quiet_NaN();
  few.pixels[static_cast<std::size_t>(30 * cols + 5)] = std::numeric_limits<float>::infinity();
  few.pixels[0] = -std::numeric_limits<float>::infinity();
  write_image_float(few, scan.projection_path(1));
  Image many = read_image(scan.projection_path(4));
  for (std::size_t i = 0; i < many.pixels.size(); i += 50) many.pixels[i] = std::numeric_limits<float>::quiet_NaN();  // 2 %
  write_image_float(many, scan.projection_path(4));

  const Measurements m = load_measurements(scan, read_geometry(dir / "truth-geometry.json"));
  EXPECT_EQ(m.view_indices, (std::vector<int>{0, 1, 2, 3, 5}));
  ASSERT_EQ(m.line_integrals.views, 5);
  ASSERT_EQ(m.matrices.size(), 5u);
  EXPECT_EQ(m.masked_pixels, 3u);
  ASSERT_EQ(m.left_out.size(), 1u);
  EXPECT_NE(m.left_out.front().find("view 4: "), std::string::npos) << m.left_out.front();
  for (std::size_t i = 0; i < m.line_integrals.data.size(); ++i) ASSERT_TRUE(std::isfinite(m.line_integrals.data[i])) << i;
  // The NaN's neighbours are all finite: it becomes their mean.
  double sum = 0;
  for (int dr = -1; dr <= 1; ++dr)
    for (int dc = -1; dc <= 1; ++dc)
      if (dr != 0 || dc != 0) sum += clean.pixels[static_cast<std::size_t>((10 + dr) * cols + 20 + dc)];
  EXPECT_NEAR(m.line_integrals.at(1, 10, 20), sum / 8, 1e-5);
  // The view after the one left out is the scan's view 5, where it belongs.
  const Image view5 = read_image(scan.projection_path(5));
  EXPECT_TRUE(std::equal(view5.pixels.begin(), view5.pixels.end(), m.line_integrals.view(4)));
  EXPECT_TRUE(m.matrices[4].matrix().isApprox(read_geometry(dir / "truth-geometry.json").views[5].P->matrix()));
}

}  // namespace
}  // namespace ctk

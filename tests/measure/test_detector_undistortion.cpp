// Resampling a radially distorted detector's images onto the pinhole grid: a smooth image seen
// through the distortion comes back to within OpenCV's bilinear table (1/32 px), and a scan that
// declares its distortion loads as the same scan taken without it.
#include <gtest/gtest.h>

#include <cmath>

#include "../test_support.hpp"
#include "ctk/measure/detector_undistortion.hpp"
#include "ctk/measure/measurements.hpp"
#include "ctk/phantoms/scan_simulation.hpp"

namespace ctk {
namespace {

double smooth(const Eigen::Vector2d& x) { return std::sin(x.x() / 9.0) + std::cos(x.y() / 7.0) + 1e-3 * x.x() * x.y(); }

TEST(DetectorUndistortion, ASmoothImageSeenThroughTheDistortionComesBack) {
  const int cols = 120, rows = 100;
  const RadialDistortion distortion{5e-6, {55.0, 48.0}};  // 2.7 px at the far corner
  // What the detector records at measured pixel m: the ideal image where m's ray lands.
  std::vector<float> measured(static_cast<std::size_t>(cols * rows)), ideal(measured.size());
  for (int v = 0; v < rows; ++v)
    for (int u = 0; u < cols; ++u)
      measured[static_cast<std::size_t>(v * cols + u)] = static_cast<float>(smooth(distortion.ideal_from_measured({u, v})));
  const DetectorUndistortion undistortion(cols, rows, distortion);
  EXPECT_NEAR(undistortion.largest_shift_px(), 5e-6 * std::pow(std::hypot(120 - 1 - 55.0, 100 - 1 - 48.0), 3), 1e-3);
  EXPECT_GT(undistortion.pixels_measured_outside(), 0);
  undistortion.apply(measured.data(), ideal.data(), DetectorUndistortion::Outside::zero);
  double worst = 0, worst_as_measured = 0;
  int zeros_outside = 0;
  for (int v = 0; v < rows; ++v)
    for (int u = 0; u < cols; ++u) {
      const Eigen::Vector2d m = distortion.measured_from_ideal({u, v});
      const std::size_t i = static_cast<std::size_t>(v * cols + u);
      if (m.x() < -1 || m.y() < -1 || m.x() > cols || m.y() > rows) {
        zeros_outside += ideal[i] == 0.0f;
        continue;
      }
      if (m.x() < 0 || m.y() < 0 || m.x() > cols - 1 || m.y() > rows - 1) continue;  // the rim: half outside
      worst = std::max(worst, std::abs(ideal[i] - smooth({u, v})));
      worst_as_measured = std::max(worst_as_measured, std::abs(measured[i] - smooth({u, v})));
    }
  // Bilinear on curvature ~ 1/49 per px^2 errs by ~ 1/8 * 1/49; the 1/32 px table adds
  // gradient (~0.25 per px) / 64.
  EXPECT_LT(worst, 0.01);
  EXPECT_GT(worst_as_measured, 0.3);  // without resampling, the distortion shows
  EXPECT_GT(zeros_outside, 0);
}

// The same noise-free scan simulated through a distorted detector, once declaring the
// distortion and once not, against the scan taken without it.
TEST(DetectorUndistortion, ADeclaredDistortionLoadsAsTheUndistortedScan) {
  ScanSimulation sim;
  sim.setup = reference_panda_setup({96, 80, 4.5, 4.5}, 2150, 1360);
  sim.holder = reference_helix_holder();
  sim.trajectory = circular_robot_trajectory(sim.setup, 3);
  sim.output = SimulatedOutput::line_integrals;
  sim.robot_noise = {0, 0};
  const auto dir = testing::scratch_dir();
  const auto plain = dir / "plain", distorted = dir / "distorted";
  simulate_scan(sim, plain);
  // Centred near a corner, so the holder (in the middle, 30 to 70 px from it) moves by 0.5 to 7 px.
  const RadialDistortion distortion{2e-5, {10.0, 8.0}};
  sim.effects.detector_distortion = distortion;
  simulate_scan(sim, distorted);
  const Geometry geometry = read_geometry(plain / "truth-geometry.json");
  const Measurements truth = load_measurements(read_scan(plain / "scan.json"), geometry);
  ScanDescription scan = read_scan(distorted / "scan.json");
  scan.distortion = distortion;
  const Measurements undistorted = load_measurements(scan, geometry);
  MeasurementOptions as_measured_options;
  as_measured_options.undistort = false;
  const Measurements as_measured = load_measurements(scan, geometry, as_measured_options);
  EXPECT_TRUE(undistorted.notes.empty());
  EXPECT_NE(undistorted.distortion_note.find("resampled"), std::string::npos) << undistorted.distortion_note;
  EXPECT_NE(as_measured.distortion_note.find("as measured"), std::string::npos) << as_measured.distortion_note;
  EXPECT_TRUE(truth.distortion_note.empty());
  // Bilinear resampling blurs the holder's sharp edges by a fraction of a pixel, as much as a
  // small shift moves them; a shift of pixels stays when both are summed over 5 x 5 pixels.
  // Compared where the measured 5 x 5 block lies on the detector.
  auto rms_from_truth = [&](const Measurements& m) {
    double sum = 0;
    int count = 0;
    for (int k = 0; k < truth.line_integrals.views; ++k)
      for (int v = 2; v < 78; ++v)
        for (int u = 2; u < 94; ++u) {
          const Eigen::Vector2d at = distortion.measured_from_ideal({u, v});
          if (at.x() < 4 || at.y() < 4 || at.x() > 91 || at.y() > 75) continue;
          double e = 0;
          for (int dv = -2; dv <= 2; ++dv)
            for (int du = -2; du <= 2; ++du)
              e += m.line_integrals.at(k, v + dv, u + du) - truth.line_integrals.at(k, v + dv, u + du);
          sum += e * e;
          ++count;
        }
    EXPECT_GT(count, 500);
    return std::sqrt(sum / count);
  };
  const double resampled = rms_from_truth(undistorted), raw = rms_from_truth(as_measured);
  EXPECT_LT(resampled, 0.1 * raw) << "resampled " << resampled << ", as measured " << raw;
}

}  // namespace
}  // namespace ctk

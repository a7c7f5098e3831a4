// The rotation axis' column from conjugate rays: on an analytic fan-beam sinogram (both rotation
// senses, the axis off the detector centre) and on three real FleX-ray fan-beam scans whose
// detector was moved sideways by a commanded 0.25 mm (3.342 px) between them.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "../test_support.hpp"
#include "ctk/measure/projection_reading.hpp"
#include "ctk/recon/conjugate_rays.hpp"
#include "ctk/recon/repeat_exposure.hpp"

namespace ctk {
namespace {

// Three discs off the axis (x, y, radius in mm, attenuation per mm): the source at distance sod
// from the axis, angle beta; column u's ray leaves the central ray by (u - u0) pitch on a detector
// sdd away, the detector's u axis turned by `orientation` (+1 or -1) against the rotation.
FanSinogram analytic_sinogram(double u0, int orientation) {
  FanSinogram s;
  s.views = 720;
  s.cols = 256;
  s.step_rad = 2 * M_PI / 720;
  s.first_angle_rad = 0.3;
  s.pitch_mm = 0.4;
  s.source_to_detector_mm = 500;
  const double sod = 400;
  const double discs[][4] = {{12, -5, 9, 0.02}, {-20, 14, 6, 0.05}, {3, 22, 4, 0.08}};
  s.values.resize(static_cast<std::size_t>(s.views * s.cols));
  for (int k = 0; k < s.views; ++k) {
    const double beta = s.first_angle_rad + k * s.step_rad;
    const Eigen::Vector2d source(sod * std::cos(beta), sod * std::sin(beta)), centre = -source.normalized();
    const Eigen::Vector2d across = orientation * Eigen::Vector2d(-std::sin(beta), std::cos(beta));
    for (int u = 0; u < s.cols; ++u) {
      const Eigen::Vector2d dir = (centre * s.source_to_detector_mm + across * (u - u0) * s.pitch_mm).normalized();
      double p = 0;
      for (const auto& d : discs) {
        const Eigen::Vector2d to = Eigen::Vector2d(d[0], d[1]) - source;
        const double along = to.dot(dir), off2 = to.squaredNorm() - along * along;
        if (off2 < d[2] * d[2]) p += 2 * std::sqrt(d[2] * d[2] - off2) * d[3];
      }
      s.values[static_cast<std::size_t>(k * s.cols + u)] = static_cast<float>(p);
    }
  }
  return s;
}

TEST(ConjugateRays, FindsTheAxisOnAnAnalyticSinogramInEitherSense) {
  for (int orientation : {+1, -1})
    for (double u0 : {131.37, 118.8}) {
      const ConjugateRayEstimate e = conjugate_ray_u0(analytic_sinogram(u0, orientation), 127.5, 20);
      std::cout << "orientation " << orientation << ", u0 " << u0 << ": found " << e.u0_px << " +- " << e.standard_error_px
                << " (sense " << e.sense << ", mismatch " << e.rms_mismatch << " against " << e.rms_mismatch_other_sense << ")\n";
      EXPECT_NEAR(e.u0_px, u0, 0.05);
      EXPECT_LT(e.standard_error_px, 0.05);
      EXPECT_LT(e.rms_mismatch, 0.2 * e.rms_mismatch_other_sense);
    }
  FanSinogram half = analytic_sinogram(128, 1);
  half.views = 300;
  half.values.resize(300 * 256);
  EXPECT_THROW(conjugate_ray_u0(half, 127.5), std::invalid_argument);
}

// One row of 1944 columns at 0.0748 mm, 3601 views of 0.1 deg; counts with a dark and two flats.
FanSinogram flexray_fan_beam(const std::string& which) {
  ScanDescription scan;
  scan.folder = testing::shared_data_dir() / "flexray-fanbeam-detector-shifts" / which;
  scan.detector = Detector{1944, 1, 0.0748, 0.0748};
  scan.projections.files_pattern = "scan_%06d.tif";
  scan.projections.count = 3601;
  scan.projections.kind = ProjectionKind::counts;
  scan.projections.flat = {"io000000.tif", "io000001.tif"};
  scan.projections.dark = {"di000000.tif"};
  const std::optional<FlatDark> flat_dark = read_flat_dark(scan);
  FanSinogram s;
  s.views = scan.projections.count;
  s.cols = scan.detector.cols;
  s.step_rad = 0.1 * M_PI / 180;
  s.pitch_mm = 0.0748;
  s.source_to_detector_mm = 527.99707;
  for (int v = 0; v < s.views; ++v) {
    const Image p = read_line_integrals(scan, v, flat_dark);
    s.values.insert(s.values.end(), p.pixels.begin(), p.pixels.end());
  }
  return s;
}

TEST(ConjugateRays, FollowsTheCommandedDetectorStepsOfARealFanBeamScan) {
  std::vector<double> u0;
  for (const char* which : {"minus", "zero", "plus"}) {
    const ConjugateRayEstimate e = conjugate_ray_u0(flexray_fan_beam(which), 971.5, 30);
    std::cout << which << ": u0 " << e.u0_px << " +- " << e.standard_error_px << " px (sense " << e.sense << ", mismatch "
              << e.rms_mismatch << " against " << e.rms_mismatch_other_sense << " the other way, " << e.pairs << " pairs)\n";
    EXPECT_LT(e.standard_error_px, 0.1);
    EXPECT_LT(e.rms_mismatch, 0.5 * e.rms_mismatch_other_sense);
    u0.push_back(e.u0_px);
  }
  // 0.25 mm / 0.0748 mm = 3.342 px per step, both steps the same way.
  const double first = u0[1] - u0[0], second = u0[2] - u0[1];
  EXPECT_NEAR(std::abs(first), 3.342, 0.2);
  EXPECT_NEAR(std::abs(second), 3.342, 0.2);
  EXPECT_GT(first * second, 0);
}

// A scan that ends with a new exposure at its first angle: the last row against the first tells a
// still object (shift within its standard error) from one moved by half a pixel, in noise.
TEST(RepeatExposure, TellsAStillObjectFromOneMovedByHalfAPixel) {
  const FanSinogram still = analytic_sinogram(128, 1), moved = analytic_sinogram(128.5, 1);
  EXPECT_FALSE(compare_repeat_exposure(still).has_value()) << "720 views of half a degree end short of the first angle";
  std::mt19937 random(7);
  std::normal_distribution<float> noise(0.0f, 0.002f);
  for (const auto& [repeat, shift] : {std::pair{&still, 0.0}, std::pair{&moved, 0.5}}) {
    FanSinogram s = still;
    s.values.insert(s.values.end(), repeat->values.begin(), repeat->values.begin() + s.cols);
    ++s.views;
    for (float& v : s.values) v += noise(random);
    const auto r = compare_repeat_exposure(s);
    ASSERT_TRUE(r.has_value());
    std::cout << "moved by " << shift << " px: found " << r->shift_px << " +- " << r->shift_sigma_px << " px\n";
    EXPECT_EQ(r->last_view, 720);
    EXPECT_NEAR(std::abs(r->shift_px), shift, 3 * r->shift_sigma_px + 0.01);
    EXPECT_EQ(r->moved(), shift > 0);
  }
}

}  // namespace
}  // namespace ctk

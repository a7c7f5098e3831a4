// The contrast loss's search on agreements of known shape: the sample's mean squared residual a
// parabola in the trial rate, so the rate, its standard error and the trials stepped through are
// known exactly.
#include <gtest/gtest.h>

#include <cmath>
#include <initializer_list>

#include "ctk/calib/contrast_loss.hpp"

namespace ctk {
namespace {

constexpr int kViews = 24, kSpheres = 40;

// Every sphere's squared residual: `floor` (1 + v / 10) + `curvature` (rate - best)^2 in view v, a
// view (`failing`) not calibrated at rates above 0.5.
struct ParabolicSample {
  explicit ParabolicSample(double best_rate) : best(best_rate) {}
  double best, floor = 0.01, curvature = 0.05;
  int failing = -1;
  std::vector<double> asked;
  ScanCalibration operator()(const CalibrationOptions& o) {
    asked.push_back(o.contrast_loss);
    ScanCalibration c;
    c.views.resize(kViews);
    for (int v = 0; v < kViews; ++v) {
      ViewCalibration& view = c.views[static_cast<std::size_t>(v)];
      if (v == failing && o.contrast_loss > 0.5) continue;  // rejected
      view.status = ViewStatus::ok;
      view.spheres_used = kSpheres;
      const double residual = std::sqrt(floor * (1 + 0.1 * v) + curvature * (o.contrast_loss - best) * (o.contrast_loss - best));
      for (int k = 0; k < kSpheres; ++k) {
        view.spheres.push_back(k);
        view.fitted_px.emplace_back(10.0 * k, 5.0);
        view.detected_px.push_back(view.fitted_px.back() + Eigen::Vector2d(residual, 0));
      }
    }
    return c;
  }
};

// The trial rates, in steps of 0.2.
std::vector<double> steps(std::initializer_list<int> k) {
  std::vector<double> rates;
  for (int s : k) rates.push_back(s * 0.2);
  return rates;
}

ContrastLossMeasurement measured(ParabolicSample& sample) {
  return measure_contrast_loss([&](const CalibrationOptions& o) { return sample(o); }, CalibrationOptions{});
}

TEST(ContrastLoss, TheParabolasVertexWithItsStandardError) {
  ParabolicSample sample(0.27);
  const ContrastLossMeasurement m = measured(sample);
  EXPECT_NEAR(m.rate, 0.27, 1e-9);
  EXPECT_EQ(sample.asked, (std::vector<double>{0, 0.2, 0.4, 0.2 - 0.1, 0.2 + 0.1}));
  // 960 spheres' 1,920 numbers less 144 pose parameters; the mean floor is 0.01 x 2.15.
  const double variance = 0.01 * 2.15 * 960 / (1920 - 144);
  EXPECT_NEAR(m.sigma, std::sqrt(variance / (960 * 0.05)), 1e-9);
  EXPECT_TRUE(m.used);
  EXPECT_EQ(m.views, kViews);
  EXPECT_EQ(m.spheres, kViews * kSpheres);  // (view, sphere) pairs
}

TEST(ContrastLoss, StepsOnWhileTheAgreementImprovesThenHalfSteps) {
  ParabolicSample far(0.93);
  EXPECT_NEAR(measured(far).rate, 0.93, 1e-9);
  std::vector<double> expected = steps({0, 1, 2, 3, 4, 5, 6});
  expected.insert(expected.end(), {1.0 - 0.1, 1.0 + 0.1});
  EXPECT_EQ(far.asked, expected);
}

TEST(ContrastLoss, NearZeroHalfAStepAboveAndNeverBelowZero) {
  ParabolicSample small(0.04);
  const ContrastLossMeasurement m = measured(small);
  EXPECT_EQ(small.asked, (std::vector<double>{0, 0.2, 0.1}));
  EXPECT_NEAR(m.rate, 0.04, 1e-9);
  EXPECT_TRUE(m.used);
  // A contrast that grows with the background is no loss: another error of the model.
  ParabolicSample below(-0.13);
  const ContrastLossMeasurement none = measured(below);
  EXPECT_EQ(below.asked, (std::vector<double>{0, 0.2, 0.1}));
  EXPECT_EQ(none.rate, 0);
  EXPECT_FALSE(none.used);
}

TEST(ContrastLoss, AnAgreementThatDoesNotCareIsNotAMeasurement) {
  ParabolicSample flat(0.4);
  flat.curvature = 0;  // no sphere on a varying background: every rate fits alike
  const ContrastLossMeasurement m = measured(flat);
  EXPECT_FALSE(std::isfinite(m.sigma));
  EXPECT_FALSE(m.used);
}

TEST(ContrastLoss, OnlyViewsCalibratedAtEveryTrialAreCompared) {
  ParabolicSample sample(0.55);
  sample.failing = 3;  // gone from the trials above 0.5: left out of every trial's mean
  const ContrastLossMeasurement m = measured(sample);
  EXPECT_NEAR(m.rate, 0.55, 1e-9);
  EXPECT_EQ(m.views, kViews - 1);
}

TEST(ContrastLoss, TheRangesEndIsNotAMeasurement) {
  ParabolicSample beyond(5.0);
  const ContrastLossMeasurement m = measured(beyond);
  EXPECT_NEAR(m.rate, kMostContrastLoss, 1e-9);
  EXPECT_FALSE(std::isfinite(m.sigma));
  EXPECT_FALSE(m.used);
}

TEST(ContrastLoss, SampleViewsSpreadOverTheScan) {
  EXPECT_EQ(contrast_sample_views(8, 4), (std::vector<int>{1, 3, 5, 7}));
  EXPECT_EQ(contrast_sample_views(3, 24), (std::vector<int>{0, 1, 2}));
}

}  // namespace
}  // namespace ctk

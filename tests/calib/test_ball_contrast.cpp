// The balls' contrast over the background behind them: the loss per unit line integral recovered
// from (background, amplitude) pairs with noise and a few wrong balls, and none found where there
// is none.
#include <gtest/gtest.h>

#include <random>

#include "ctk/calib/ball_contrast.hpp"

namespace ctk {
namespace {

std::vector<Eigen::Vector2d> pairs(double hardening, int n, std::uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> background(0.2, 1.6);
  std::normal_distribution<double> noise(0.0, 0.0004);
  std::vector<Eigen::Vector2d> out;
  for (int i = 0; i < n; ++i) {
    const double b = background(rng);
    out.emplace_back(b, 0.029 * (1 - hardening * b) + noise(rng));
  }
  return out;
}

TEST(BallContrast, RecoversTheLossAndDropsWrongBalls) {
  std::vector<Eigen::Vector2d> p = pairs(0.3, 300, 1);
  for (int i = 0; i < 10; ++i) p.emplace_back(0.5 + 0.1 * i, 0.05);  // balls on a sample's edge, say
  const BallContrast c = fit_ball_contrast(p);
  EXPECT_NEAR(c.hardening, 0.3, 3 * c.sigma + 1e-3);
  EXPECT_LT(c.sigma, 0.01);
  EXPECT_EQ(c.balls, 300);
  EXPECT_TRUE(c.significant());
}

TEST(BallContrast, NoneWhereThereIsNone) {
  int significant = 0;
  for (std::uint32_t seed = 1; seed <= 50; ++seed) significant += fit_ball_contrast(pairs(0.0, 200, seed)).significant();
  EXPECT_LE(significant, 2);                                         // one-sided 3 sigma: 0.13 % per scan
  EXPECT_FALSE(fit_ball_contrast(pairs(0.3, 10, 1)).significant());  // too few balls to say
  EXPECT_EQ(fit_ball_contrast({}).balls, 0);
}

}  // namespace
}  // namespace ctk

// The shared median: odd and even counts (the upper middle value), unsorted input, nothing. The
// paired z-score against a hand computation, and its cases without spread. The chi-square
// threshold against tabulated quantiles; the Wald statistic against a hand computation and with
// a gauge's free direction.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <stdexcept>

#include "ctk/core/statistics.hpp"

namespace ctk {
namespace {

TEST(Statistics, MedianIsTheMiddleValueOfAnyOrder) {
  EXPECT_DOUBLE_EQ(median(std::vector<double>{5, 1, 4, 2, 3}), 3.0);
  EXPECT_DOUBLE_EQ(median(std::vector<double>{4, 1, 3, 2}), 3.0);  // upper of 2 and 3
  EXPECT_FLOAT_EQ(median(std::vector<float>{-2.5f}), -2.5f);
  EXPECT_DOUBLE_EQ(median(std::vector<double>{}), 0.0);
  std::vector<double> kept{9, 7, 8};
  EXPECT_DOUBLE_EQ(median(kept), 8.0);
  EXPECT_EQ(kept, (std::vector<double>{9, 7, 8}));  // the copy leaves the input alone
  EXPECT_DOUBLE_EQ(median_in_place(kept), 8.0);
}

TEST(Statistics, PairedZIsTheMeanImprovementInStandardErrors) {
  // Differences 1, 2, 3: mean 2, sample variance 1, standard error 1 / sqrt(3).
  EXPECT_NEAR(paired_z({5, 6, 7}, {4, 4, 4}), 2.0 * std::sqrt(3.0), 1e-12);
  EXPECT_NEAR(paired_z({4, 4, 4}, {5, 6, 7}), -2.0 * std::sqrt(3.0), 1e-12);  // worse after
  EXPECT_DOUBLE_EQ(paired_z({3, 3}, {1, 1}), 1e9);                            // the same gain everywhere
  EXPECT_DOUBLE_EQ(paired_z({1, 1}, {3, 3}), -1e9);
  EXPECT_DOUBLE_EQ(paired_z({2, 5}, {2, 5}), 0.0);
  EXPECT_DOUBLE_EQ(paired_z({}, {}), 0.0);
}

TEST(Statistics, ChiSquareThresholdIsTheUpperQuantile) {
  EXPECT_NEAR(chi_square_threshold(0.05, 1), 3.841459, 1e-6);  // 1.96^2
  EXPECT_NEAR(chi_square_threshold(0.01, 3), 11.344867, 1e-6);
  EXPECT_NEAR(chi_square_threshold(0.001, 6), 22.457744, 1e-6);
  EXPECT_THROW(chi_square_threshold(0.0, 2), std::invalid_argument);
  EXPECT_THROW(chi_square_threshold(0.05, 0), std::invalid_argument);
}

TEST(Statistics, WaldStatisticWeighsEachDirectionByItsVarianceAndSkipsAGauge) {
  // Independent: (3 / 1)^2 + (1 / 0.5)^2 = 13.
  Eigen::Matrix2d independent;
  independent << 1, 0, 0, 0.25;
  WaldStatistic w = wald_statistic(Eigen::Vector2d(3, 1), independent);
  EXPECT_NEAR(w.chi2, 13.0, 1e-12);
  EXPECT_EQ(w.dof, 2);
  // Correlated: v' C^-1 v with C = [[2, 1], [1, 2]], v = (1, 1): C^-1 v = (1/3, 1/3), so 2/3.
  Eigen::Matrix2d correlated;
  correlated << 2, 1, 1, 2;
  EXPECT_NEAR(wald_statistic(Eigen::Vector2d(1, 1), correlated).chi2, 2.0 / 3.0, 1e-12);
  // A gauge leaves (1, -1) free: only the constrained direction (1, 1) / sqrt(2), variance 2, counts.
  Eigen::Matrix2d gauge;
  gauge << 1, 1, 1, 1;
  w = wald_statistic(Eigen::Vector2d(2, 0), gauge);  // along (1, 1) / sqrt(2): sqrt(2), squared 2, over 2
  EXPECT_NEAR(w.chi2, 1.0, 1e-9);
  EXPECT_EQ(w.dof, 1);
  EXPECT_EQ(wald_statistic(Eigen::VectorXd(), Eigen::MatrixXd()).dof, 0);  // no covariance: nothing judged
}

}  // namespace
}  // namespace ctk

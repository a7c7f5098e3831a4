// The shared median: odd and even counts (the upper middle value), unsorted input, nothing. The
// paired z-score against a hand computation, and its cases without spread.
#include <gtest/gtest.h>

#include <cmath>

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

}  // namespace
}  // namespace ctk

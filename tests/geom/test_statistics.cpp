// The shared median: odd and even counts (the upper middle value), unsorted input, nothing.
#include <gtest/gtest.h>

#include "ctk/geom/statistics.hpp"

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

}  // namespace
}  // namespace ctk

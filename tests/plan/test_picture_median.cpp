// The 3 x 3 x 3 median the planner reads its picture through: a lone voxel is gone, a plane step
// and a plate two voxels thick stay exactly where they were, a plate one voxel thick is gone, and
// the border (neighbourhood clamped) keeps a constant volume constant; a box filters its voxels as
// the whole volume's median does and leaves the rest as they were.
#include <gtest/gtest.h>

#include "ctk/plan/picture_median.hpp"

namespace ctk {
namespace {

template <typename F>
Volume volume_of(F mu) {  // 9 x 8 x 7 voxels, `mu(i, j, k)`
  Volume v(VolumeLayout::centred({9, 8, 7}, Eigen::Vector3d::Constant(1.0)));
  for (int k = 0; k < 7; ++k)
    for (int j = 0; j < 8; ++j)
      for (int i = 0; i < 9; ++i) v.at(i, j, k) = static_cast<float>(mu(i, j, k));
  return v;
}

void expect_equal(const Volume& a, const Volume& b) {
  ASSERT_EQ(a.layout, b.layout);
  for (std::size_t v = 0; v < a.layout.voxel_count(); ++v) ASSERT_EQ(a.data[v], b.data[v]) << v;
}

TEST(PictureMedian, RemovesALoneVoxelAndKeepsAConstantVolumeToTheBorder) {
  const Volume constant = volume_of([](int, int, int) { return 0.02; });
  expect_equal(median_3x3x3(constant), constant);
  Volume spike = constant;
  spike.at(4, 4, 3) = 1.0f;   // a streak's crossing, or noise
  spike.at(0, 0, 0) = -1.0f;  // in a corner: 8 of its clamped 27 neighbours are itself
  expect_equal(median_3x3x3(spike), constant);
}

TEST(PictureMedian, KeepsAStepAndAPlateTwoVoxelsThickAndRemovesOneVoxelThick) {
  const Volume step = volume_of([](int i, int, int) { return i < 4 ? 0.0 : 0.07; });
  expect_equal(median_3x3x3(step), step);
  const Volume thick = volume_of([](int i, int, int) { return i == 4 || i == 5 ? 0.07 : 0.0; });
  expect_equal(median_3x3x3(thick), thick);
  const Volume thin = volume_of([](int i, int, int) { return i == 4 ? 0.07 : 0.0; });
  expect_equal(median_3x3x3(thin), volume_of([](int, int, int) { return 0.0; }));
  // A plane ramp (values all different) keeps every voxel: the median of a window on a plane
  // through its centre is the centre.
  const Volume ramp = volume_of([](int i, int j, int k) { return 0.01 * i + 0.001 * j + 0.0001 * k; });
  const Volume r = median_3x3x3(ramp);
  for (int k = 1; k < 6; ++k)
    for (int j = 1; j < 7; ++j)
      for (int i = 1; i < 8; ++i) EXPECT_EQ(r.at(i, j, k), ramp.at(i, j, k)) << i << " " << j << " " << k;
}

TEST(PictureMedian, ABoxFiltersItsVoxelsAsTheWholeDoesAndCopiesTheRest) {
  const Volume ramp = volume_of([](int i, int j, int k) { return (i * 7 + j * 3 + k * 5) % 11 * 0.01; });
  const Volume whole = median_3x3x3(ramp);
  const Volume boxed = median_3x3x3(ramp, VoxelBox{{-3, 2, 1}, {5, 8, 40}});  // clipped to the volume
  int filtered = 0;
  for (int k = 0; k < 7; ++k)
    for (int j = 0; j < 8; ++j)
      for (int i = 0; i < 9; ++i) {
        const bool in = i < 5 && j >= 2 && k >= 1;
        EXPECT_EQ(boxed.at(i, j, k), (in ? whole : ramp).at(i, j, k)) << i << " " << j << " " << k;
        filtered += in && whole.at(i, j, k) != ramp.at(i, j, k);
      }
  EXPECT_GT(filtered, 50);  // the median does change this volume inside the box
}

}  // namespace
}  // namespace ctk

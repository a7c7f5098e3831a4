// The comparison's figures against what they must be on volumes made to measure: an exact copy
// scores no error and the truth's own edge gradient, a brighter copy a proportionally steeper
// one, a blurred copy a shallower one (along the blurred axis only), and the three-profile figure agrees with the all-lines one
// on a cube (every line through it crosses the same edges). The RMSE outside the absorbers
// leaves out the absorbers' own level and their face neighbours, and only those. The level-matched
// RMSE forgives each material a level of its own and nothing else.
#include <gtest/gtest.h>

#include <cmath>

#include "ctk/plan/trajectory_quality.hpp"

namespace ctk {
namespace {

// 32^3 voxels of 0.5 mm with an 8-voxel cube of 0.05 /mm in the middle.
Volume cube() {
  Volume v(VolumeLayout::centred({32, 32, 32}, Eigen::Vector3d::Constant(0.5)));
  for (int k = 12; k < 20; ++k)
    for (int j = 12; j < 20; ++j)
      for (int i = 12; i < 20; ++i) v.at(i, j, k) = 0.05f;
  return v;
}

constexpr float kNoAbsorber = 1.0f;  // above every truth value here

// Neighbour averaging (1/4, 1/2, 1/4) along x.
Volume blurred_along_x(const Volume& v) {
  Volume b = v;
  const auto& n = v.layout.size;
  for (int k = 0; k < n[2]; ++k)
    for (int j = 0; j < n[1]; ++j)
      for (int i = 1; i + 1 < n[0]; ++i)
        b.at(i, j, k) = 0.25f * v.at(i - 1, j, k) + 0.5f * v.at(i, j, k) + 0.25f * v.at(i + 1, j, k);
  return b;
}

TEST(TrajectoryQuality, EdgeGradientsFollowContrastAndSharpness) {
  const Volume truth = cube();
  const SampleRegion region;
  const std::array<int, 3> through = centre_of_mass_voxel(truth, region);
  EXPECT_EQ(through, (std::array<int, 3>{16, 16, 16}));

  const TrajectoryQuality same = trajectory_quality(truth, truth, region, through, kNoAbsorber);
  EXPECT_EQ(same.rmse_per_mm, 0.0);
  // Every edge is a full step of 0.05 /mm over 0.5 mm.
  EXPECT_NEAR(same.truth_edge_gradient_per_mm2, 0.1, 1e-6);
  EXPECT_NEAR(same.edge_gradient_per_mm2, 0.1, 1e-6);
  EXPECT_NEAR(same.profile_gradient_per_mm2, 0.1, 1e-6);

  Volume brighter = truth;
  for (float& x : brighter.data) x *= 1.2f;
  const TrajectoryQuality b = trajectory_quality(brighter, truth, region, through, kNoAbsorber);
  EXPECT_NEAR(b.edge_gradient_per_mm2, 0.12, 1e-6);
  EXPECT_NEAR(b.rmse_per_mm, 0.01 * std::sqrt(512.0 / 32768.0), 1e-6);  // 0.01 on the cube's 512 of 32768 voxels
  EXPECT_DOUBLE_EQ(b.rmse_outside_absorbers_per_mm, b.rmse_per_mm);     // nothing is an absorber

  // Blurring along x halves the steps across the x faces (1/4 -> 3/4 of the step); across the y
  // and z faces the first and last columns keep 3/4 of theirs, the six between all of it:
  // (1/2 + 2 x (2 x 3/4 + 6) / 8) / 3 of the truth's.
  const TrajectoryQuality s = trajectory_quality(blurred_along_x(truth), truth, region, through, kNoAbsorber);
  EXPECT_NEAR(s.edge_gradient_per_mm2, 0.1 * (0.5 + 2 * 7.5 / 8) / 3, 1e-6);
  // Per axis: the x faces alone are halved; along y and z, 7.5 of 8 columns' steps are kept.
  EXPECT_NEAR(s.edge_gradient_along_per_mm2[0], 0.05, 1e-6);
  EXPECT_NEAR(s.edge_gradient_along_per_mm2[1], 0.1 * 7.5 / 8, 1e-6);
  EXPECT_NEAR(s.edge_gradient_along_per_mm2[2], 0.1 * 7.5 / 8, 1e-6);
  for (double along : same.edge_gradient_along_per_mm2) EXPECT_NEAR(along, 0.1, 1e-6);
  EXPECT_NEAR(s.profile_gradient_per_mm2, 0.1 * (0.5 + 1 + 1) / 3, 1e-6);
}

TEST(TrajectoryQuality, RmseOutsideAbsorbersLeavesOutTheirLevelAndTheirNeighbours) {
  const Volume truth = cube();  // the cube is the absorber
  const float absorber_above = 0.04f;
  const SampleRegion region;
  const std::array<int, 3> through = centre_of_mass_voxel(truth, region);
  Volume x = truth;
  for (float& v : x.data)
    if (v > 0) v = 0.07f;    // the absorber's level is off, as under beam hardening
  x.at(20, 16, 16) = 0.02f;  // a face neighbour of the cube: partial volume
  x.at(21, 21, 16) = 0.02f;  // an edge neighbour: counted
  x.at(3, 4, 5) = -0.01f;    // far away: counted
  const TrajectoryQuality q = trajectory_quality(x, truth, region, through, absorber_above);
  // 32768 voxels less the cube's 512 and the 6 x 64 face neighbours.
  EXPECT_NEAR(q.rmse_outside_absorbers_per_mm, std::sqrt((0.02 * 0.02 + 0.01 * 0.01) / (32768.0 - 512 - 384)), 1e-9);
  EXPECT_NEAR(q.rmse_per_mm, std::sqrt((512 * 0.02 * 0.02 + 2 * 0.02 * 0.02 + 0.01 * 0.01) / 32768.0), 1e-9);
}

TEST(TrajectoryQuality, LevelMatchedRmseForgivesEachMaterialItsLevelAndNothingElse) {
  // Two materials: the cube (PVC) and a slab beside it (aluminium); the truth is their sum.
  const VolumeLayout layout = cube().layout;
  MaterialVolume pvc{"pvc", cube()}, aluminium{"aluminium", Volume(layout)}, absent{"copper", Volume(layout)};
  for (int k = 4; k < 8; ++k)
    for (int j = 10; j < 22; ++j)
      for (int i = 10; i < 22; ++i) aluminium.volume.at(i, j, k) = 0.08f;
  Volume truth(layout), x(layout);
  for (std::size_t v = 0; v < truth.data.size(); ++v) {
    truth.data[v] = pvc.volume.data[v] + aluminium.volume.data[v];
    x.data[v] = 1.6f * pvc.volume.data[v] + 1.3f * aluminium.volume.data[v];  // each hardened to its own level
  }
  const SampleRegion region;
  const std::array<int, 3> through = centre_of_mass_voxel(truth, region);
  const std::vector<MaterialVolume> materials{pvc, aluminium, absent};

  // Levels alone: nothing left once matched, and the levels are those put in.
  const TrajectoryQuality levels = trajectory_quality(x, truth, region, through, kNoAbsorber, materials);
  // Against the truth: 0.6 x 0.05 off on the cube's 512 voxels, 0.3 x 0.08 on the slab's 576.
  EXPECT_NEAR(levels.rmse_per_mm, std::sqrt((512 * 0.03 * 0.03 + 576 * 0.024 * 0.024) / 32768.0), 1e-7);
  EXPECT_NEAR(levels.rmse_level_matched_per_mm, 0.0, 1e-7);
  ASSERT_EQ(levels.material_levels.size(), 2u);  // copper has no voxel: left out
  EXPECT_EQ(levels.material_levels[0].material, "pvc");
  EXPECT_NEAR(levels.material_levels[0].level, 1.6, 1e-5);
  EXPECT_EQ(levels.material_levels[1].material, "aluminium");
  EXPECT_NEAR(levels.material_levels[1].level, 1.3, 1e-5);

  // An error in the air is not a level: it counts in full and leaves the levels alone.
  Volume streaked = x;
  streaked.at(3, 4, 5) = 0.02f;
  const TrajectoryQuality s = trajectory_quality(streaked, truth, region, through, kNoAbsorber, materials);
  EXPECT_NEAR(s.rmse_level_matched_per_mm, 0.02 / std::sqrt(32768.0), 1e-8);
  EXPECT_NEAR(s.material_levels[0].level, 1.6, 1e-5);

  // Blur is not a level either: it is still counted, and on the hardened copy it grows with the
  // levels (by a factor between the two materials' 1.3 and 1.6).
  const TrajectoryQuality blurred = trajectory_quality(blurred_along_x(truth), truth, region, through, kNoAbsorber, materials);
  const TrajectoryQuality blurred_hardened =
      trajectory_quality(blurred_along_x(x), truth, region, through, kNoAbsorber, materials);
  EXPECT_GT(blurred.rmse_level_matched_per_mm, 0.001);
  const double growth = blurred_hardened.rmse_level_matched_per_mm / blurred.rmse_level_matched_per_mm;
  EXPECT_GT(growth, 1.3);
  EXPECT_LT(growth, 1.6);

  // Without the split nothing is matched; a split on another grid is refused.
  EXPECT_EQ(trajectory_quality(x, truth, region, through, kNoAbsorber).rmse_level_matched_per_mm, 0.0);
  const std::vector<MaterialVolume> elsewhere{{"pvc", Volume(VolumeLayout::centred({8, 8, 8}, Eigen::Vector3d::Constant(0.5)))}};
  EXPECT_THROW(trajectory_quality(x, truth, region, through, kNoAbsorber, elsewhere), std::invalid_argument);
}

}  // namespace
}  // namespace ctk

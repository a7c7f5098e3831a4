#include "ctk/geom/trajectory.hpp"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <numeric>

#include "ctk/geom/sphere_map.hpp"

namespace ctk {
namespace {

TEST(Healpix, ViewCountIsTwelveNsideSquared) {
  for (int nside : {1, 2, 3, 8}) {
    const HealpixSphere s(nside);
    EXPECT_EQ(s.size(), 12 * nside * nside);
    for (int i = 0; i < s.size(); ++i) {
      EXPECT_NEAR(s.direction(i).norm(), 1.0, 1e-12);
      EXPECT_EQ(s.cell_of(s.direction(i)), i);
    }
  }
  EXPECT_EQ(HealpixSphere(3).size(), 108);  // the reference system's scout sphere
}

TEST(Healpix, CellsHaveEqualAreaOnTheEqualAreaMap) {
  // Count random uniform directions per cell: each cell gets its equal share (a chi-square bound),
  // and the same holds for strips of equal area on the map.
  const HealpixSphere s(2);
  const auto dirs = random_directions(96000, 11);
  std::vector<int> hits(static_cast<std::size_t>(s.size()), 0);
  for (const auto& d : dirs) ++hits[static_cast<std::size_t>(s.cell_of(d))];
  const double expected = 96000.0 / s.size();
  double chi2 = 0;
  for (int h : hits) chi2 += (h - expected) * (h - expected) / expected;
  EXPECT_LT(chi2, 47 + 4 * std::sqrt(2 * 47.0));  // 47 degrees of freedom, ~4 sigma
  EXPECT_NEAR(s.cell_area_sr() * s.size(), 4 * M_PI, 1e-12);

  // On the map, equal-height strips hold equal numbers of uniform directions (equal area).
  std::array<int, 8> strips{};
  for (const auto& d : dirs) {
    const MapPoint p = equal_area_map(d);
    ++strips[static_cast<std::size_t>(std::min(7, static_cast<int>((p.y + 1) / 2 * 8)))];
  }
  for (int n : strips) EXPECT_NEAR(n, 12000, 5 * std::sqrt(12000.0));
  EXPECT_NEAR(equal_area_map_total_area(), 4 * M_PI, 1e-12);
}

TEST(SphereMap, RoundTrip) {
  for (const auto& d : random_directions(50, 3)) {
    EXPECT_LT((from_equal_area_map(equal_area_map(d)) - d).norm(), 1e-9);
  }
}

TEST(Neighbours, HealpixDiscAgreesWithBruteForce) {
  const HealpixSphere s(8);
  const auto dirs = s.directions();
  const double radius = 20.0 * M_PI / 180;
  for (int i : {0, 100, 383, 767}) {
    auto brute = neighbours_within(dirs, i, radius);
    brute.push_back(i);
    std::sort(brute.begin(), brute.end());
    EXPECT_EQ(s.cells_within(dirs[static_cast<std::size_t>(i)], radius), brute);
  }
}

TEST(Trajectory, CircularRotationsAreEvenlySpaced) {
  const Eigen::Vector3d axis = Eigen::Vector3d(0.2, 1, 0.1).normalized();
  const auto R = circular_rotations(axis, 36, 0.1, 2 * M_PI);
  ASSERT_EQ(R.size(), 36u);
  for (std::size_t k = 0; k + 1 < R.size(); ++k) {
    const Eigen::AngleAxisd step(R[k + 1] * R[k].transpose());
    EXPECT_NEAR(step.angle(), 2 * M_PI / 36, 1e-12);
    EXPECT_LT((step.axis() - axis).norm(), 1e-9);
  }
}

TEST(Trajectory, RotationLookingAlongPutsTheDirectionOnTheBeam) {
  for (const auto& d : random_directions(40, 5)) {
    const Eigen::Matrix3d R = rotation_looking_along(d);
    EXPECT_NEAR(R.determinant(), 1.0, 1e-12);
    EXPECT_LT((R * d - Eigen::Vector3d::UnitZ()).norm(), 1e-12);
    // The holder axis points up in the image (camera -y), never down.
    EXPECT_LE((R * Eigen::Vector3d::UnitZ()).y(), 1e-12);
  }
  const Eigen::Matrix3d along_axis = rotation_looking_along(Eigen::Vector3d::UnitZ());
  EXPECT_NEAR(along_axis.determinant(), 1.0, 1e-12);
}

TEST(Trajectory, RandomDirectionsAreReproducibleAndUniform) {
  EXPECT_EQ(random_directions(10, 42)[3], random_directions(10, 42)[3]);
  EXPECT_NE(random_directions(10, 42)[3], random_directions(10, 43)[3]);
  const auto dirs = random_directions(20000, 1);
  const Eigen::Vector3d mean = std::accumulate(dirs.begin(), dirs.end(), Eigen::Vector3d::Zero().eval()) / 20000.0;
  EXPECT_LT(mean.norm(), 4 * std::sqrt(1.0 / 20000));
}

TEST(Trajectory, SpinningCapCoversItsBandInEqualAreasWhileSpinning) {
  const double lo = 5 * M_PI / 180, hi = 90 * M_PI / 180;
  const auto dirs = spinning_cap_directions(400, lo, hi);
  ASSERT_EQ(dirs.size(), 400u);
  int within_10_deg = 0;
  for (std::size_t k = 0; k < dirs.size(); ++k) {
    EXPECT_NEAR(dirs[k].norm(), 1.0, 1e-12);
    const double polar = std::acos(dirs[k].z());
    EXPECT_GE(polar, lo);
    EXPECT_LE(polar, hi);
    within_10_deg += polar < 10 * M_PI / 180;
    if (k > 0) {  // the spin between consecutive views is the golden angle (mod 2 pi)
      const double turn =
          std::remainder(std::atan2(dirs[k].y(), dirs[k].x()) - std::atan2(dirs[k - 1].y(), dirs[k - 1].x()), 2 * M_PI);
      EXPECT_NEAR(turn, M_PI * (3 - std::sqrt(5.0)), 1e-9);
    }
  }
  // Equal areas: the share within 10 deg of the axis is that band's share of the cap's area.
  const double share = (std::cos(lo) - std::cos(10 * M_PI / 180)) / (std::cos(lo) - std::cos(hi));
  EXPECT_NEAR(within_10_deg, share * 400, 1.0);
  EXPECT_THROW(spinning_cap_directions(10, 0.5, 0.4), std::invalid_argument);
}

}  // namespace
}  // namespace ctk

#include "ctk/geom/helix.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace ctk {
namespace {

TEST(Helix, ReferenceHolderSpheresLieOnTheHelix) {
  const Holder h = reference_helix_holder();
  ASSERT_EQ(h.spheres_mm.size(), 50u);
  EXPECT_DOUBLE_EQ(h.tau_min(), -40.0);
  EXPECT_DOUBLE_EQ(h.tau_max(), 40.0);
  for (const auto& s : h.spheres_mm) {
    EXPECT_NEAR(std::hypot(s.x(), s.y()), 28.0, 1e-12);
    EXPECT_LT((h.helix.at(h.helix.nearest_tau(s)) - s).norm(), 1e-9);
  }
  // Two turns over the 80 mm: the phase advances 4 pi.
  EXPECT_NEAR(h.helix.rho_rad_per_mm * 80.0, 4 * M_PI, 1e-12);
}

TEST(Helix, TangentIsTheDerivative) {
  const Helix helix{28, 0.157, 0.3};
  for (double tau : {-30.0, 0.0, 12.5}) {
    const Eigen::Vector3d fd = (helix.at(tau + 1e-6) - helix.at(tau - 1e-6)) / 2e-6;
    EXPECT_LT((fd - helix.tangent(tau)).norm(), 1e-6);
  }
}

TEST(Helix, ClosestPointOnProjectedHelixIsContinuousAndExact) {
  const Helix helix{28, 4 * M_PI / 80, 0.0};
  const Intrinsics K{2150 / 0.6, 2150 / 0.6, 0, 359.5, 359.5};
  const auto P =
      ProjectionMatrix::compose(K, make_rigid(rotation_about(Eigen::Vector3d(1, 0.2, 0), 1.4), Eigen::Vector3d(0.3, -0.2, 1360)));
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> tau_dist(-38, 38), off(-0.6, 0.6);
  for (int i = 0; i < 50; ++i) {
    const double tau = tau_dist(rng);
    // A pixel on the curve is found at distance 0 and at its own tau (where the curve does not cross itself).
    const Eigen::Vector2d on = P.project(helix.at(tau));
    const HelixPoint hp = closest_point_on_projected_helix(P, helix, on, -40, 40);
    EXPECT_LT(hp.distance_px, 1e-6);
    // A pixel nudged off the curve: the answer is a true local minimum (perpendicular foot).
    const Eigen::Vector2d near = on + Eigen::Vector2d(off(rng), off(rng));
    const HelixPoint q = closest_point_on_projected_helix(P, helix, near, -40, 40);
    EXPECT_LE(q.distance_px, (near - on).norm() + 1e-9);
    Eigen::Matrix<double, 2, 3> J;
    P.project(helix.at(q.tau), &J);
    const Eigen::Vector2d dir = J * helix.tangent(q.tau);
    EXPECT_LT(std::abs((q.uv - near).dot(dir.normalized())), 1e-6);
  }
}

TEST(HolderWall, ChordIsThePathInsideTheShell) {
  const HolderWall wall{25.0, 28.0, std::nullopt};
  // Across the axis: twice the wall; between the radii: the outer circle's chord; outside: none.
  EXPECT_NEAR(wall.chord_mm({-100, 0, 5}, {1, 0, 0}), 6.0, 1e-12);
  EXPECT_NEAR(wall.chord_mm({-100, 26, 0}, {3, 0, 0}), 2 * std::sqrt(28.0 * 28 - 26 * 26), 1e-12);
  EXPECT_EQ(wall.chord_mm({-100, 28.5, 0}, {1, 0, 0}), 0.0);
  // Tilted 45 deg towards the axis: the same cross-section, a longer path; along the axis: none.
  EXPECT_NEAR(wall.chord_mm({0, 0, 0}, {1, 0, 1}), 6.0 * std::sqrt(2.0), 1e-12);
  EXPECT_EQ(wall.chord_mm({26, 0, 0}, {0, 0, 1}), 0.0);
  // Random lines against marching along them in 1 um steps and counting the steps inside.
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> u(-1, 1);
  for (int i = 0; i < 10; ++i) {
    const Eigen::Vector3d point(30 * u(rng), 30 * u(rng), 10 * u(rng));
    const Eigen::Vector3d direction = Eigen::Vector3d(u(rng), u(rng), 0.5 * u(rng)).normalized();
    double inside = 0;
    const double step = 1e-3;
    for (double s = -150; s < 150; s += step) {
      const Eigen::Vector3d x = point + (s + 0.5 * step) * direction;
      const double r = std::hypot(x.x(), x.y());
      if (r >= 25.0 && r < 28.0) inside += step;
    }
    EXPECT_NEAR(wall.chord_mm(point, 2.5 * direction), inside, 0.01) << i;
  }
}

TEST(HolderWall, ATubeWithEndsIsCutByThem) {
  const HolderWall tube{25.0, 28.0, Eigen::Vector2d(-59, 59)};
  // Along a line 3 deg off the axis, tangent to the wall's middle: an infinite tube's chord is
  // the 2D chord (18 mm) over sin 3 deg; the tube's is at most its length over cos 3 deg.
  const Eigen::Vector3d direction(0, std::sin(3 * M_PI / 180), std::cos(3 * M_PI / 180));
  const HolderWall infinite{25.0, 28.0, std::nullopt};
  EXPECT_NEAR(infinite.chord_mm({26.5, 0, 0}, direction), 2 * std::sqrt(28.0 * 28 - 26.5 * 26.5) / std::sin(3 * M_PI / 180),
              1e-9);
  EXPECT_LE(tube.chord_mm({26.5, 0, 0}, direction), 118 / std::cos(3 * M_PI / 180) + 1e-9);
  // Across the axis beyond an end: nothing; inside the ends: as if infinite.
  EXPECT_EQ(tube.chord_mm({-100, 0, 60}, {1, 0, 0}), 0.0);
  EXPECT_NEAR(tube.chord_mm({-100, 0, 58}, {1, 0, 0}), 6.0, 1e-12);
  // Random lines, steep ones among them, against marching in 1 um steps.
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> u(-1, 1);
  for (int i = 0; i < 12; ++i) {
    const Eigen::Vector3d point(30 * u(rng), 30 * u(rng), 60 * u(rng));
    const Eigen::Vector3d line = Eigen::Vector3d(0.3 * u(rng), 0.3 * u(rng), 1.0).normalized();
    double inside = 0;
    const double step = 1e-3;
    for (double s = -400; s < 400; s += step) {
      const Eigen::Vector3d x = point + (s + 0.5 * step) * line;
      const double r = std::hypot(x.x(), x.y());
      if (r >= 25.0 && r < 28.0 && std::abs(x.z()) <= 59) inside += step;
    }
    EXPECT_NEAR(tube.chord_mm(point, 2.5 * line), inside, 0.01) << i;
  }
}

}  // namespace
}  // namespace ctk

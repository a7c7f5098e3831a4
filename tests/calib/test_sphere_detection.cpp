// Sphere detection on a synthetic end-on view of the reference holder: the tube (POM, radii 25 and
// 28 mm, 118 mm long) seen 2 deg from its axis is a ring of line integral up to about 3.5 with
// steep edges, and the spheres sit on its outer edge. The plain detector's planar background and
// wide Gaussian see the edge there; the remainder after a running median keeps the bumps.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <iostream>
#include <random>
#include <vector>

#include "ctk/calib/sphere_detection.hpp"
#include "ctk/geom/helix.hpp"

namespace ctk {
namespace {

constexpr double kRadius = 2.6;  // px, the reference holder's spheres at its magnification

struct EndOnView {
  Image image;
  std::vector<Eigen::Vector2d> centres;
};

// The reference setup's camera (2150 mm to a detector of 0.6 mm pixels, the holder 1360 mm from
// the source) looking 2 deg from the holder's axis; 4 x 4 rays per pixel, POM 0.03 /mm, the balls
// 0.12 /mm, noise 0.01 (the reference scans').
EndOnView end_on_view() {
  constexpr int kSize = 240;
  const Holder holder = reference_helix_holder();
  const double f = 2150 / 0.6, centre = 0.5 * (kSize - 1);
  const Eigen::Matrix3d R = Eigen::AngleAxisd(2 * M_PI / 180, Eigen::Vector3d(1, 1, 0).normalized()).toRotationMatrix();
  const Eigen::Vector3d t(0.4, -0.3, 1360);           // holder origin in the camera frame
  const Eigen::Vector3d source = -R.transpose() * t;  // in the holder frame
  EndOnView view;
  for (const auto& X : holder.spheres_mm) {
    const Eigen::Vector3d c = R * X + t;
    view.centres.push_back({f * c.x() / c.z() + centre, f * c.y() / c.z() + centre});
  }
  view.image = Image{kSize, kSize, std::vector<float>(static_cast<std::size_t>(kSize * kSize))};
  std::mt19937 rng(3);
  std::normal_distribution<double> noise(0, 0.01);
  const double ball = 0.5 * holder.sphere_diameter_mm;
  for (int r = 0; r < kSize; ++r)
    for (int c = 0; c < kSize; ++c) {
      double value = 0;
      for (int i = 0; i < 4; ++i)
        for (int j = 0; j < 4; ++j) {
          const Eigen::Vector3d ray =
              (R.transpose() * Eigen::Vector3d((c - 0.5 + (j + 0.5) / 4 - centre) / f, (r - 0.5 + (i + 0.5) / 4 - centre) / f, 1))
                  .normalized();
          double v = 0.03 * holder.wall->chord_mm(source, ray);
          for (const auto& X : holder.spheres_mm) {
            const double miss2 = (X - source).cross(ray).squaredNorm();
            if (miss2 < ball * ball) v += 0.12 * 2 * std::sqrt(ball * ball - miss2);
          }
          value += v / 16;
        }
      view.image.pixels[static_cast<std::size_t>(r * kSize + c)] = static_cast<float>(value + noise(rng));
    }
  return view;
}

// How many of the balls have a detection within `within` px, and how many detections are near none.
std::pair<int, int> found(const EndOnView& view, const std::vector<SphereDetection>& detections, double within) {
  int hits = 0, strays = 0;
  for (const auto& centre : view.centres) {
    bool hit = false;
    for (const auto& d : detections) hit = hit || (d.uv - centre).norm() <= within;
    hits += hit;
  }
  for (const auto& d : detections) {
    bool near = false;
    for (const auto& centre : view.centres) near = near || (d.uv - centre).norm() <= 2 * kRadius;
    strays += !near;
  }
  return {hits, strays};
}

TEST(SphereDetection, FindsSpheresOnTheSteepEdgeOfAnEndOnWall) {
  const EndOnView view = end_on_view();
  // The balls that stand apart (two turns of the helix seen end on pair up, so half of them touch).
  std::vector<Eigen::Vector2d> apart;
  for (const auto& a : view.centres) {
    double nearest = 1e9;
    for (const auto& b : view.centres)
      if (&a != &b) nearest = std::min(nearest, (a - b).norm());
    if (nearest > 2 * kRadius + 4) apart.push_back(a);
  }
  const EndOnView apart_view{view.image, apart};
  DetectionOptions o;
  o.radius_px = kRadius;
  const auto plain = found(apart_view, detect_spheres(view.image, o), 0.6);
  o.edge_preserving_background = true;
  const auto median = detect_spheres(view.image, o);
  const auto [hits, strays] = found(apart_view, median, 0.6);
  const auto all = found(view, median, 0.6);
  std::cout << "of " << apart.size() << " balls standing apart on the ring's edge, found within 0.6 px: " << plain.first
            << " plainly, " << hits << " over the running median (" << all.first << " of all " << view.centres.size() << "; "
            << all.second << " detections near no ball)\n";
  ASSERT_GE(apart.size(), 10u);
  EXPECT_GE(hits, static_cast<int>(0.8 * static_cast<double>(apart.size())));
  EXPECT_GE(hits, plain.first + 5);
  EXPECT_LE(all.second, 10);  // the ring's edges may leave a few; the pattern's match sorts them out
}

TEST(SphereDetection, TheRunningMedianFindsWhatThePlainDetectorFindsOnAFlatBackground) {
  // Balls on a sloping plane: both backgrounds find every ball, at the same place to 0.3 px.
  constexpr int kSize = 96;
  std::vector<Eigen::Vector2d> centres;
  for (int k = 0; k < 9; ++k) centres.push_back({18.3 + 29.1 * (k % 3), 17.7 + 29.4 * (k / 3)});
  Image image{kSize, kSize, std::vector<float>(static_cast<std::size_t>(kSize * kSize))};
  for (int r = 0; r < kSize; ++r)
    for (int c = 0; c < kSize; ++c) {
      double value = 0.4 + 0.01 * c - 0.004 * r;
      for (const auto& centre : centres)
        value += 0.15 * std::sqrt(std::max(0.0, 1 - (Eigen::Vector2d(c, r) - centre).squaredNorm() / (kRadius * kRadius)));
      image.pixels[static_cast<std::size_t>(r * kSize + c)] = static_cast<float>(value);
    }
  DetectionOptions o;
  o.radius_px = kRadius;
  const auto plain = detect_spheres(image, o);
  o.edge_preserving_background = true;
  const auto median = detect_spheres(image, o);
  ASSERT_EQ(plain.size(), centres.size());
  ASSERT_EQ(median.size(), centres.size());
  for (const auto& d : median) {
    double nearest = 1e9;
    for (const auto& p : plain) nearest = std::min(nearest, (p.uv - d.uv).norm());
    EXPECT_LE(nearest, 0.3);
  }
}

}  // namespace
}  // namespace ctk

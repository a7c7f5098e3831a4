// The profile fit against the centroid on synthetic sphere images: a ball's chord profile drawn
// with 8 x 8 rays per pixel (not the fit's own 3 x 3) on a sloping background, at random
// sub-pixel centres, with and without noise of the level (10^4 counts: ~0.01 per pixel).
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "ctk/calib/sphere_profile_fit.hpp"

namespace ctk {
namespace {

constexpr double kRadius = 2.6;  // px, the 2 mm spheres at magnification 1.58, 0.6 mm pixels

Image sphere_image(const Eigen::Vector2d& centre, double noise, std::mt19937& rng) {
  Image im{32, 32, std::vector<float>(32 * 32)};
  std::normal_distribution<double> gauss(0, noise);
  for (int r = 0; r < im.rows; ++r)
    for (int c = 0; c < im.cols; ++c) {
      double chord = 0;
      for (int i = 0; i < 8; ++i)
        for (int j = 0; j < 8; ++j) {
          const double x = c - 0.5 + (j + 0.5) / 8 - centre.x(), y = r - 0.5 + (i + 0.5) / 8 - centre.y();
          chord += 2 * std::sqrt(std::max(0.0, kRadius * kRadius - x * x - y * y)) / 64;
        }
      // 0.075 /mm aluminium, chord in mm = chord_px / radius (1 mm sphere radius); wall background.
      const double wall = 0.4 + 0.01 * c - 0.004 * r;
      im.pixels[static_cast<std::size_t>(r * im.cols + c)] =
          static_cast<float>(wall + 0.075 * chord / kRadius + (noise > 0 ? gauss(rng) : 0.0));
    }
  return im;
}

struct Scatter {
  double centroid = 0, profile = 0;  // RMS centre error per axis, px
};

Scatter centre_errors(double noise, int trials) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> offset(-0.5, 0.5);
  double centroid = 0, profile = 0;
  for (int t = 0; t < trials; ++t) {
    const Eigen::Vector2d truth(15.5 + offset(rng), 16.0 + offset(rng));
    const Image im = sphere_image(truth, noise, rng);
    SphereDetection d;
    EXPECT_TRUE(refine_centroid(im, truth.array().round().matrix(), kRadius, d));
    centroid += (d.uv - truth).squaredNorm() / 2;
    EXPECT_TRUE(refine_by_profile_fit(im, kRadius, d));
    profile += (d.uv - truth).squaredNorm() / 2;
  }
  return {std::sqrt(centroid / trials), std::sqrt(profile / trials)};
}

TEST(SphereProfileFit, ExactWithoutNoise) {
  const Scatter s = centre_errors(0.0, 50);
  std::cout << "noise-free centre error per axis: centroid " << s.centroid << " px, profile fit " << s.profile << " px\n";
  EXPECT_LE(s.profile, 0.005);
}

TEST(SphereProfileFit, ScattersLessThanTheCentroidUnderPhotonNoise) {
  const Scatter s = centre_errors(0.011, 400);
  std::cout << "centre error per axis at 10^4 counts: centroid " << s.centroid << " px, profile fit " << s.profile << " px\n";
  EXPECT_LE(s.profile, 0.75 * s.centroid);
  EXPECT_LE(s.profile, 0.05);
}

TEST(SphereProfileFit, RefusesAWindowOffTheImage) {
  std::mt19937 rng(1);
  const Image im = sphere_image({15.5, 16}, 0, rng);
  SphereDetection d;
  d.uv = {1.0, 16.0};
  EXPECT_FALSE(refine_by_profile_fit(im, kRadius, d));
  EXPECT_EQ(d.uv, Eigen::Vector2d(1.0, 16.0));
}

}  // namespace
}  // namespace ctk

// The profile fit against the centroid on synthetic sphere images: a ball's chord profile drawn
// with 8 x 8 rays per pixel (not the fit's own 3 x 3) on a sloping background, at random
// sub-pixel centres, with and without noise of the reference level (10^4 counts: ~0.01 per pixel);
// a ball on a tube wall's silhouette, and two touching balls.
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

#include "ctk/calib/sphere_profile_fit.hpp"

namespace ctk {
namespace {

constexpr double kRadius = 2.6;  // px, the reference holder's 2 mm spheres at magnification 1.58, 0.6 mm pixels

// The wall background of the plain tests: a sloping plane.
double sloping_wall(double u, double v) { return 0.4 + 0.01 * u - 0.004 * v; }

// Balls at `centres` on `background` (evaluated per ray), 8 x 8 rays per pixel; each ray's ball
// chord scaled by exp(-contrast_loss x background), as a beam hardened by the background scales it.
template <typename Background>
Image balls_image(const std::vector<Eigen::Vector2d>& centres, double noise, std::mt19937& rng, Background background,
                  int size = 32, double contrast_loss = 0) {
  Image im{size, size, std::vector<float>(static_cast<std::size_t>(size * size))};
  std::normal_distribution<double> gauss(0, noise);
  for (int r = 0; r < im.rows; ++r)
    for (int c = 0; c < im.cols; ++c) {
      double value = 0;
      for (int i = 0; i < 8; ++i)
        for (int j = 0; j < 8; ++j) {
          const double u = c - 0.5 + (j + 0.5) / 8, v = r - 0.5 + (i + 0.5) / 8;
          const double under = background(u, v);
          value += under / 64;
          // 0.075 /mm aluminium, chord in mm = chord_px / radius (1 mm sphere radius).
          for (const auto& centre : centres) {
            const double x = u - centre.x(), y = v - centre.y();
            value += std::exp(-contrast_loss * under) * 0.075 * 2 * std::sqrt(std::max(0.0, kRadius * kRadius - x * x - y * y)) /
                     kRadius / 64;
          }
        }
      im.pixels[static_cast<std::size_t>(r * im.cols + c)] = static_cast<float>(value + (noise > 0 ? gauss(rng) : 0.0));
    }
  return im;
}

Image sphere_image(const Eigen::Vector2d& centre, double noise, std::mt19937& rng) {
  return balls_image({centre}, noise, rng, sloping_wall);
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

// A tube wall seen side on (parallel rays across columns): path length through a shell of radii
// 16 and 20 px whose axis is column 2, times POM's 0.027 /mm at 0.38 mm per px.
double shell_path_px(double u) {
  const double x = u - 2.0;
  auto chord = [x](double radius) { return x * x < radius * radius ? 2 * std::sqrt(radius * radius - x * x) : 0.0; };
  return chord(20.0) - chord(16.0);
}
double tube_wall(double u, double v) { return 0.05 + 0.001 * v + 0.027 * 0.38 * shell_path_px(u); }

TEST(SphereProfileFit, ABallOnTheWallSilhouetteNeedsTheWallsShape) {
  // The ball straddles the shell's outer edge (column 22), where the wall's shadow falls from its
  // steepest to nothing within the window: a plane cannot follow it, the known shape can.
  std::mt19937 rng(3);
  const Eigen::Vector2d truth(20.3, 16.2);
  const Image im = balls_image({truth}, 0, rng, tube_wall);
  const BackgroundShape shape = [](const Eigen::Vector2d& uv) { return shell_path_px(uv.x()); };
  SphereDetection plane, known;
  plane.uv = known.uv = truth + Eigen::Vector2d(0.3, -0.2);
  ASSERT_TRUE(refine_by_profile_fit(im, kRadius, known, {}, shape));
  EXPECT_LT((known.uv - truth).norm(), 0.01) << known.uv.transpose();
  // Without it the centre is pulled (or the fit gives up); either way it is not where the ball is.
  if (refine_by_profile_fit(im, kRadius, plane)) {
    std::cout << "plane background: centre off by " << (plane.uv - truth).norm() << " px\n";
    EXPECT_GT((plane.uv - truth).norm(), 0.05);
  }
  // The fitted strength is the ball's: 0.075 /mm x (4/3) pi r^3 in px^2 mm with r = 1 mm = 2.6 px.
  const double expected = 0.075 / kRadius * 4 * M_PI / 3 * kRadius * kRadius * kRadius;
  EXPECT_NEAR(known.strength, expected, 0.02 * expected);
}

TEST(SphereProfileFit, ABallOnTheSilhouetteUnderAHardenedBeamNeedsTheContrastLoss) {
  // The ball's contrast falls by 30 % per unit of the wall's line integral (a polychromatic beam
  // behind a plastic wall, as the reference orbits at 70-120 kV measure it): across the ball the
  // wall's shadow rises steeply, so a fit with a constant contrast leans the centre towards the
  // thinner side; with the rate the centre is as good as under a monochromatic beam.
  std::mt19937 rng(3);
  const Eigen::Vector2d truth(20.3, 16.2), start = truth + Eigen::Vector2d(0.3, -0.2);
  constexpr double kLoss = 0.3;
  const BackgroundShape shape = [](const Eigen::Vector2d& uv) { return shell_path_px(uv.x()); };
  ProfileFitOptions with_loss;
  with_loss.contrast_loss = kLoss;
  const auto error = [&](const Image& im, const ProfileFitOptions& o) {
    SphereDetection d;
    d.uv = start;
    EXPECT_TRUE(refine_by_profile_fit(im, kRadius, d, o, shape));
    return (d.uv - truth).norm();
  };
  const double monochromatic = error(balls_image({truth}, 0, rng, tube_wall), {});
  const Image hardened = balls_image({truth}, 0, rng, tube_wall, 32, kLoss);
  const double constant = error(hardened, {}), modelled = error(hardened, with_loss);
  std::cout << "centre off by " << monochromatic << " px (monochromatic beam); hardened beam: " << constant
            << " px with a constant contrast, " << modelled << " px with the contrast loss\n";
  EXPECT_LT(std::abs(modelled - monochromatic), 0.002);
  EXPECT_GT(constant - monochromatic, 0.01);
  // On a flat background the rate changes nothing (the window's contrast is constant).
  const Image flat = balls_image(
      {Eigen::Vector2d(15.3, 16.4)}, 0, rng, [](double, double) { return 0.4; }, 32, kLoss);
  SphereDetection a, b;
  a.uv = b.uv = {15.5, 16.0};
  ASSERT_TRUE(refine_by_profile_fit(flat, kRadius, a, with_loss));
  ASSERT_TRUE(refine_by_profile_fit(flat, kRadius, b));
  EXPECT_LT((a.uv - b.uv).norm(), 1e-4);
}

TEST(SphereProfileFit, TouchingBallsAreFittedTogether) {
  // Two balls 5 px apart share most of their windows: fitted alone, each is pulled towards the
  // other; fitted together both are exact.
  std::mt19937 rng(4);
  const std::vector<Eigen::Vector2d> truth{{13.2, 15.6}, {17.9, 17.3}};
  const Image im = balls_image(truth, 0, rng, sloping_wall);
  std::vector<SphereDetection> pair(2);
  pair[0].uv = truth[0] + Eigen::Vector2d(0.2, 0.3);
  pair[1].uv = truth[1] + Eigen::Vector2d(-0.3, 0.1);
  std::vector<SphereDetection> alone = pair;
  const std::vector<bool> refined = refine_cluster_by_profile_fit(im, kRadius, pair);
  for (int b = 0; b < 2; ++b) {
    ASSERT_TRUE(refined[static_cast<std::size_t>(b)]);
    EXPECT_LT((pair[static_cast<std::size_t>(b)].uv - truth[static_cast<std::size_t>(b)]).norm(), 0.01) << b;
    if (refine_by_profile_fit(im, kRadius, alone[static_cast<std::size_t>(b)])) {
      const double off = (alone[static_cast<std::size_t>(b)].uv - truth[static_cast<std::size_t>(b)]).norm();
      std::cout << "ball " << b << " fitted alone: off by " << off << " px\n";
      EXPECT_GT(off, 0.05);
    }
  }
}

}  // namespace
}  // namespace ctk

// FDK from matrices: circle fit and refusal of non-circular scans, Parker weights, and the value
// of a reconstructed uniform ball from exact (analytic) projections, full and short scans.
#include <gtest/gtest.h>

#include "ctk/geom/trajectory.hpp"
#include "ctk/phantoms/render.hpp"
#include "ctk/recon/fdk.hpp"

namespace ctk {
namespace {

const Detector kDetector{96, 80, 1.1, 1.1};

std::vector<ProjectionMatrix> circular_views(int count, double span_rad) {
  const Intrinsics K = Intrinsics::from_setup(1500, kDetector, kDetector.centre_px() + Eigen::Vector2d(0.7, -0.4));
  std::vector<ProjectionMatrix> views;
  // The holder axis w is the rotation axis and appears along v.
  for (int i = 0; i < count; ++i) {
    const double a = span_rad * i / count;
    const Eigen::Vector3d d(std::cos(a), std::sin(a), 0);
    views.push_back(ProjectionMatrix::compose(K, make_rigid(rotation_looking_along(d), Eigen::Vector3d(0, 0, 1000))));
  }
  return views;
}

TEST(Fdk, CircleFitFindsRadiusAndArcAndRefusesASphericalScan) {
  const CircularTrajectory full = fit_circular_trajectory(circular_views(120, 2 * M_PI));
  EXPECT_NEAR(full.radius_mm, 1000, 1e-6);
  EXPECT_NEAR(full.arc_rad, 2 * M_PI, 1e-9);
  EXPECT_NEAR(full.step_rad[7], 2 * M_PI / 120, 1e-9);
  const CircularTrajectory part = fit_circular_trajectory(circular_views(100, 4.0));
  EXPECT_NEAR(part.arc_rad, 4.0 * 99 / 100, 1e-9);
  EXPECT_NEAR(part.angles_rad.front(), 0.0, 1e-9);
  std::vector<ProjectionMatrix> spherical;
  const Intrinsics K = Intrinsics::from_setup(1500, kDetector, kDetector.centre_px());
  for (const auto& d : random_directions(50, 4))
    spherical.push_back(ProjectionMatrix::compose(K, make_rigid(rotation_looking_along(d), Eigen::Vector3d(0, 0, 1000))));
  try {
    fit_circular_trajectory(spherical);
    FAIL() << "a spherical scan must be refused";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("circular trajectory"), std::string::npos) << e.what();
  }
}

TEST(Fdk, ParkerWeightsOfConjugateRaysSumToOne) {
  const double arc = M_PI + 2 * 0.3;
  for (double beta = 0; beta <= arc; beta += 0.01)
    for (double gamma = -0.25; gamma <= 0.25; gamma += 0.05) {
      double sum = parker_weight(beta, gamma, arc);
      for (double conjugate : {beta + M_PI + 2 * gamma, beta - M_PI + 2 * gamma}) sum += parker_weight(conjugate, -gamma, arc);
      ASSERT_NEAR(sum, 1.0, 1e-9) << beta << ", " << gamma;
    }
}

// Mean over a 12^3 block at the ball's centre, relative to its attenuation. Off the axis, so a
// wrong sign in the fan angle of the Parker weights would show.
double ball_centre_value(double span_rad, int count) {
  const double mu = 0.02;
  const Phantom ball{"ball", {Primitive::sphere(Eigen::Vector3d(4.0, -3.2, 0), 12, mu)}};
  const auto views = circular_views(count, span_rad);
  ProjectionStack b(count, kDetector.rows, kDetector.cols);
  for (int v = 0; v < count; ++v) {
    const Image im = render_line_integrals(ball, views[static_cast<std::size_t>(v)], kDetector, {1, std::nullopt, std::nullopt});
    std::copy(im.pixels.begin(), im.pixels.end(), b.view(v));
  }
  Volume x(VolumeLayout::centred({48, 48, 48}, Eigen::Vector3d::Constant(0.8)));
  fdk_reconstruct(views, b, kDetector, x, RampWindow::ram_lak);
  double sum = 0;
  int n = 0;
  for (int k = 18; k < 30; ++k)
    for (int j = 14; j < 26; ++j)
      for (int i = 23; i < 35; ++i) {
        sum += x.at(i, j, k);
        ++n;
      }
  return sum / n / mu;
}

TEST(Fdk, UniformBallComesBackAtItsAttenuation) {
  const double full = ball_centre_value(2 * M_PI, 180), short_scan = ball_centre_value(220 * M_PI / 180, 180);
  std::cout << "ball centre / truth: full turn " << full << ", 220 deg " << short_scan << "\n";
  // Exact data, a smooth interior: both within 0.2 % (a wrong fan-angle sign in the Parker
  // weights gives +0.5 % here).
  EXPECT_NEAR(full, 1.0, 0.002);
  // A short scan: 220 degrees (pi + 2 x 20 deg; the fan is +-2.5 deg here).
  EXPECT_NEAR(short_scan, 1.0, 0.002);
}

}  // namespace
}  // namespace ctk

// A fan-beam scan on a cone-beam toolkit: a one-row detector in the mid-plane of a circular orbit
// and a one-slice volume. The projector must stay adjoint and the solver must bring back a disc
// from its analytic line integrals.
#include <gtest/gtest.h>

#include <cmath>
#include <iostream>
#include <random>

#include "ctk/geom/scan_import.hpp"
#include "ctk/proj/joseph_operator.hpp"
#include "ctk/recon/wls_cg.hpp"

namespace ctk {
namespace {

const Detector kFan{192, 1, 0.8, 0.8};

std::vector<ProjectionMatrix> fan_orbit(int views) {
  CircularOrbit orbit;
  orbit.detector = kFan;
  orbit.principal_point_px = {95.5, 0.0};
  orbit.source_to_axis_mm = 400;
  orbit.source_to_detector_mm = 600;
  for (int k = 0; k < views; ++k) orbit.angles_rad.push_back(2 * M_PI * k / views);
  return circular_matrices(orbit);
}

// Chord of the ray through pixel (u, 0) with the disc of radius r about c in the plane z = 0.
double chord(const ProjectionMatrix& P, double u, const Eigen::Vector2d& c, double r) {
  const Eigen::Vector3d s = P.source_position(), d = P.ray_direction({u, 0.0});
  const Eigen::Vector2d s2 = s.head<2>(), d2 = d.head<2>().normalized();
  const double along = (c - s2).dot(d2), dist2 = (c - s2).squaredNorm() - along * along;
  return dist2 < r * r ? 2 * std::sqrt(r * r - dist2) : 0.0;
}

TEST(FanBeam, OneRowOneSliceIsAdjointAndReconstructsADisc) {
  const auto views = fan_orbit(180);
  const VolumeLayout layout = VolumeLayout::centred({96, 96, 1}, Eigen::Vector3d(0.6, 0.6, 0.6));
  const JosephProjector A;

  // Adjointness on random data.
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> U(-1, 1);
  Volume x(layout), Aty(layout);
  for (float& v : x.data) v = U(rng);
  ProjectionStack y(180, 1, kFan.cols), Ax(180, 1, kFan.cols);
  for (float& v : y.data) v = U(rng);
  A.forward(x, views, Ax);
  A.back(y, views, Aty);
  double lhs = 0, rhs = 0, nAx = 0, ny = 0;
  for (std::size_t i = 0; i < y.data.size(); ++i)
    lhs += double(Ax.data[i]) * y.data[i], nAx += double(Ax.data[i]) * Ax.data[i], ny += double(y.data[i]) * y.data[i];
  for (std::size_t i = 0; i < x.data.size(); ++i) rhs += double(x.data[i]) * Aty.data[i];
  EXPECT_GT(nAx, 0);
  EXPECT_LT(std::abs(lhs - rhs) / std::sqrt(nAx * ny), 1e-5);

  // A disc of 0.02 / mm, radius 15 mm, off centre.
  const Eigen::Vector2d c(4, -3);
  const double r = 15, mu = 0.02;
  ProjectionStack b(180, 1, kFan.cols);
  for (int v = 0; v < 180; ++v)
    for (int u = 0; u < kFan.cols; ++u)
      b.at(v, 0, u) = static_cast<float>(mu * chord(views[static_cast<std::size_t>(v)], u, c, r));
  Volume rec(layout);
  WlsOptions o;
  o.iterations = 60;
  o.tolerance = 0;
  solve_wls_cg(JosephOperator(views, layout, 1, kFan.cols), b, nullptr, rec, o);
  double inside = 0, outside = 0;
  int n_in = 0, n_out = 0;
  for (int j = 0; j < 96; ++j)
    for (int i = 0; i < 96; ++i) {
      const double d = (layout.centre_of(i, j, 0).head<2>() - c).norm();
      if (d < r - 2) inside += rec.at(i, j, 0), ++n_in;
      if (d > r + 2 && d < 25) outside += std::abs(rec.at(i, j, 0)), ++n_out;
    }
  std::cout << "disc " << inside / n_in << " outside " << outside / n_out << "\n";
  EXPECT_NEAR(inside / n_in, mu, 0.03 * mu);
  EXPECT_LT(outside / n_out, 0.05 * mu);
}

}  // namespace
}  // namespace ctk

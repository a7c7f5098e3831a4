// The fast projector's ray preparation (SIMD across rays) against march_ray, the scalar
// preparation the reference projector marches with, and against the definition of the interior
// range the kernels' mask-free paths rely on.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <random>

#include "ctk/geom/trajectory.hpp"
#include "ctk/proj/ray_geometry.hpp"
#include "ray_table.hpp"
#include "simd_targets.hpp"

namespace ctk {
namespace {

struct View {
  VolumeLayout layout;
  ViewRays rays;
  int cols = 0, rows = 0;
};

// A random volume seen from anywhere (now and then from inside it, or along an axis).
View random_view(std::mt19937_64& rng) {
  std::uniform_real_distribution<double> u(0, 1);
  View v;
  v.layout = VolumeLayout::centred(
      {10 + static_cast<int>(80 * u(rng)), 10 + static_cast<int>(80 * u(rng)), 10 + static_cast<int>(80 * u(rng))},
      Eigen::Vector3d(0.5 + u(rng), 0.5 + u(rng), 0.5 + u(rng)));
  v.cols = 200, v.rows = 150;
  const double sod = u(rng) < 0.2 ? 10 + 30 * u(rng) : 200 + 800 * u(rng);
  const Detector det{v.cols, v.rows, 0.3 + 2 * u(rng), 0.3 + 2 * u(rng)};
  Eigen::Vector3d d(u(rng) - 0.5, u(rng) - 0.5, u(rng) - 0.5);
  if (u(rng) < 0.2) d = Eigen::Vector3d(0, 1, 0);
  const Eigen::Matrix3d R =
      Eigen::AngleAxisd(6.3 * u(rng), Eigen::Vector3d::UnitZ()).toRotationMatrix() * rotation_looking_along(d.normalized());
  const Intrinsics K = Intrinsics::from_setup(1.5 * sod, det, det.centre_px());
  v.rays = view_rays(ProjectionMatrix::compose(K, make_rigid(R, Eigen::Vector3d(0, 0, sod))), v.layout);
  return v;
}

// Whether the sample of a ray at slice k, from the values as the float table holds them, has all
// four bilinear corners inside the grid by the kernels' margin (1e-3 voxel).
bool interior_at(const detail::PreparedRays& p, int l, const VolumeLayout& layout, int k) {
  const int a = static_cast<int>(p.axis[l]);
  const auto [b, c] = other_axes(a);
  const double k_mid = static_cast<float>(0.5 * (layout.size[static_cast<std::size_t>(a)] - 1));
  for (const auto& [p_mid, beta, n] : {std::tuple{p.pb_mid[l], p.beta_b[l], layout.size[static_cast<std::size_t>(b)]},
                                       std::tuple{p.pc_mid[l], p.beta_c[l], layout.size[static_cast<std::size_t>(c)]}}) {
    const double position = static_cast<float>(p_mid) + (k - k_mid) * static_cast<float>(beta);
    if (!(position >= 1e-3 && position <= n - 1 - 1e-3)) return false;
  }
  return true;
}

TEST(RayPreparation, MatchesMarchRayExactlyOnEverySimdTarget) {
  std::mt19937_64 rng(17);
  std::uniform_real_distribution<double> u(0, 1);
  for (int trial = 0; trial < 40; ++trial) {
    const View v = random_view(rng);
    double pu[detail::kMaxLanes], pv[detail::kMaxLanes];
    for (int l = 0; l < detail::kMaxLanes; ++l) {  // pixels on the detector and off it
      pu[l] = std::floor(-50 + (v.cols + 100) * u(rng));
      pv[l] = std::floor(-50 + (v.rows + 100) * u(rng));
    }
    testing::on_every_simd_target([&] {
      detail::PreparedRays p;
      detail::prepare_rays(v.rays, v.layout, 0, 0, pu, pv, detail::kMaxLanes, p);
      for (int l = 0; l < detail::kMaxLanes; ++l) {
        SCOPED_TRACE("trial " + std::to_string(trial) + " lane " + std::to_string(l));
        const MarchedRay m = march_ray(v.rays, v.layout, pu[l], pv[l]);
        EXPECT_EQ(p.axis[l], m.axis);
        EXPECT_EQ(p.pb_mid[l], m.pb_mid);
        EXPECT_EQ(p.beta_b[l], m.beta_b);
        EXPECT_EQ(p.pc_mid[l], m.pc_mid);
        EXPECT_EQ(p.beta_c[l], m.beta_c);
        EXPECT_NEAR(p.weight_mm[l], m.weight_mm, 1e-14 * m.weight_mm);  // Eigen may sum the squares in another order
        EXPECT_EQ(p.k_first[l], m.k_first);
        EXPECT_EQ(p.k_last[l], m.k_last);
      }
    });
  }
}

TEST(RayPreparation, LanePixelsAreThePathsPixelsOnEverySimdTarget) {
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> u(0, 1);
  for (int trial = 0; trial < 200; ++trial) {
    detail::LanePath path;
    path.along_u = u(rng) < 0.5;
    path.slope = trial % 10 == 0 ? 0.5 : 2 * u(rng) - 1;  // halves: rounding exactly between two pixels
    path.major_first = static_cast<int>(300 * u(rng)) - 100;
    path.line_first = static_cast<int>(300 * u(rng)) - 100;
    const int line = static_cast<int>(50 * u(rng)), lane = 16 * static_cast<int>(20 * u(rng));
    const int count = 1 + static_cast<int>(detail::kMaxLanes * u(rng));
    testing::on_every_simd_target([&] {
      double pu[detail::kMaxLanes], pv[detail::kMaxLanes];
      detail::lane_pixels(path, line, lane, count, pu, pv);
      for (int l = 0; l < detail::kMaxLanes; ++l) {
        int expected_u, expected_v;
        path.pixel(line, lane + std::min(l, count - 1), expected_u, expected_v);
        EXPECT_EQ(pu[l], expected_u) << "trial " << trial << " lane " << l;
        EXPECT_EQ(pv[l], expected_v) << "trial " << trial << " lane " << l;
      }
    });
  }
}

TEST(RayPreparation, TheInteriorRangeIsExactlyWhereEveryCornerIsInside) {
  std::mt19937_64 rng(29);
  std::uniform_real_distribution<double> u(0, 1);
  int rays_with_interior = 0;
  for (int trial = 0; trial < 40; ++trial) {
    const View v = random_view(rng);
    double pu[detail::kMaxLanes], pv[detail::kMaxLanes];
    for (int l = 0; l < detail::kMaxLanes; ++l) pu[l] = std::floor(v.cols * u(rng)), pv[l] = std::floor(v.rows * u(rng));
    detail::PreparedRays p;
    detail::prepare_rays(v.rays, v.layout, 0, 0, pu, pv, detail::kMaxLanes, p);
    for (int l = 0; l < detail::kMaxLanes; ++l) {
      const int first = static_cast<int>(p.k_first[l]), last = static_cast<int>(p.k_last[l]);
      const int in_first = static_cast<int>(p.in_first[l]), in_last = static_cast<int>(p.in_last[l]);
      for (int k = first; k <= last; ++k)
        EXPECT_EQ(interior_at(p, l, v.layout, k), k >= in_first && k <= in_last)
            << "trial " << trial << " lane " << l << " slice " << k;
      rays_with_interior += in_first <= in_last;
    }
  }
  EXPECT_GT(rays_with_interior, 100);  // the check saw real interiors, not only empty ones
}

}  // namespace
}  // namespace ctk

// Voxel-driven back projection (FDK's): the SIMD kernel against the plain scalar reference on
// views that tilt, miss the detector and put voxels behind the source, and the weights of a
// constant image against their closed form.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <random>
#include <vector>

#include "ctk/geom/trajectory.hpp"
#include "ctk/proj/voxel_backprojection.hpp"
#include "simd_targets.hpp"

namespace ctk {
namespace {

double squared_norm(const FloatBuffer& a) {
  double n = 0;
  for (float e : a) n += static_cast<double>(e) * e;
  return n;
}

// |a - b| / |b|, in double.
double relative_rms(const FloatBuffer& a, const FloatBuffer& b) {
  double d = 0;
  for (std::size_t i = 0; i < a.size(); ++i) d += (static_cast<double>(a[i]) - b[i]) * (static_cast<double>(a[i]) - b[i]);
  return std::sqrt(d / squared_norm(b));
}

// A view from `direction`, source `sod` mm from `target`, detector cols x rows at 1500 mm,
// turned by `roll_deg` about the beam.
ProjectionMatrix view_of(const Eigen::Vector3d& direction, double sod, const Eigen::Vector3d& target, int cols, int rows,
                         double pitch, double roll_deg) {
  const Detector det{cols, rows, pitch, pitch};
  const Intrinsics K = Intrinsics::from_setup(1500.0, det, det.centre_px() + Eigen::Vector2d(1.3, -0.7));
  const Eigen::Matrix3d R = Eigen::AngleAxisd(roll_deg * M_PI / 180, Eigen::Vector3d::UnitZ()).toRotationMatrix() *
                            rotation_looking_along(direction.normalized());
  return ProjectionMatrix::compose(K, make_rigid(R, Eigen::Vector3d(0, 0, sod) - R * target));
}

TEST(VoxelBackprojection, AgreesWithTheScalarReference) {
  // 37 voxels per row: two full AVX-512 vectors and a tail (and 4 AVX2 ones and a tail).
  const VolumeLayout layout = VolumeLayout::centred({37, 30, 23}, Eigen::Vector3d(1.0, 1.1, 0.9));
  const int cols = 41, rows = 33;
  const std::vector<ProjectionMatrix> views = {
      view_of({1, 0.1, 0.05}, 1000, Eigen::Vector3d::Zero(), cols, rows, 1.6, 0),
      view_of({0.3, 1, 0.4}, 900, Eigen::Vector3d(3, -2, 1), cols, rows, 1.3, 30),
      view_of({0, 0, 1}, 1000, Eigen::Vector3d(25, 0, 0), cols, rows, 1.6, 0),    // half the volume off the detector
      view_of({0.2, -1, 0.1}, 8, Eigen::Vector3d::Zero(), cols, rows, 40.0, 10),  // source inside: voxels behind it
  };
  ProjectionStack q(static_cast<int>(views.size()), rows, cols);
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> value(-1.0f, 2.0f);
  for (float& e : q.data) e = value(rng);
  Volume reference(layout);
  voxel_backproject_reference(q, views, 1000.0, reference);
  // Each view alone as well (a view that contributed nothing would hide a broken path): its image
  // and its reference, made once for every target.
  std::vector<ProjectionStack> alone;
  std::vector<Volume> alone_reference;
  for (std::size_t v = 0; v < views.size(); ++v) {
    alone.emplace_back(1, rows, cols);
    std::copy(q.view(static_cast<int>(v)), q.view(static_cast<int>(v)) + q.pixels_per_view(), alone.back().view(0));
    alone_reference.emplace_back(layout);
    voxel_backproject_reference(alone.back(), {views[v]}, 1000.0, alone_reference.back());
    EXPECT_GT(squared_norm(alone_reference.back().data), 0.0) << "view " << v;
  }
  testing::on_every_simd_target([&] {
    Volume fast(layout);
    voxel_backproject(q, views, 1000.0, fast);
    EXPECT_LT(relative_rms(fast.data, reference.data), 2e-5);
    double worst = 0, largest = 0;
    for (std::size_t i = 0; i < fast.data.size(); ++i) {
      worst = std::max(worst, std::abs(static_cast<double>(fast.data[i]) - reference.data[i]));
      largest = std::max(largest, std::abs(static_cast<double>(reference.data[i])));
    }
    EXPECT_LT(worst, 1e-4 * largest);
    // With the source among the voxels (view 3), a voxel a fraction of a millimetre in front of it
    // weighs (1000 / depth)^2 ~ 1e7, and the float depth's rounding (~1e-6 mm) shows at 1e-5.
    for (std::size_t v = 0; v < views.size(); ++v) {
      Volume a(layout);
      voxel_backproject(alone[v], {views[v]}, 1000.0, a);
      EXPECT_LT(relative_rms(a.data, alone_reference[v].data), v == 3 ? 5e-5 : 1e-5) << "view " << v;
    }
  });
}

TEST(VoxelBackprojection, AConstantImageGivesTheSumOfTheWeights) {
  const VolumeLayout layout = VolumeLayout::centred({20, 20, 20}, Eigen::Vector3d::Constant(1.0));
  const int cols = 64, rows = 64;
  std::vector<ProjectionMatrix> views;
  for (int v = 0; v < 7; ++v)
    views.push_back(
        view_of({std::cos(0.9 * v), std::sin(0.9 * v), 0.3}, 1000, Eigen::Vector3d::Zero(), cols, rows, 1.6, 5.0 * v));
  ProjectionStack q(static_cast<int>(views.size()), rows, cols);
  std::fill(q.data.begin(), q.data.end(), 1.0f);
  Volume x(layout);
  voxel_backproject(q, views, 1000.0, x);
  for (const auto& [i, j, k] : {std::array<int, 3>{0, 0, 0}, {19, 7, 3}, {10, 10, 10}, {5, 19, 19}}) {
    double expected = 0;
    for (const auto& P : views) {
      const double depth = (P.matrix() * layout.centre_of(i, j, k).homogeneous()).z();
      expected += (1000.0 / depth) * (1000.0 / depth);
    }
    EXPECT_NEAR(x.at(i, j, k), expected, 1e-5 * expected) << i << " " << j << " " << k;
  }
  // A view with the whole volume behind its source adds nothing.
  const ProjectionMatrix behind = view_of({1, 0, 0}, -100, Eigen::Vector3d::Zero(), cols, rows, 1.6, 0);
  ProjectionStack one(1, rows, cols);
  std::fill(one.data.begin(), one.data.end(), 1.0f);
  voxel_backproject(one, {behind}, 1000.0, x);
  EXPECT_EQ(*std::max_element(x.data.begin(), x.data.end()), 0.0f);
}

}  // namespace
}  // namespace ctk

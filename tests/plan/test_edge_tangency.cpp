// The edges' demand for view directions: a plate wants the directions in its plane and not its
// normal, a ball (edges of every orientation) wants every direction alike, a uniform region
// wants nothing in particular; and a planner given the plate's demand puts more of its views in
// the plate's plane while staying spread, also when it reads that demand off a picture of the
// plate and some directions are out of reach, and off a noisy picture of it.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>

#include "ctk/geom/trajectory.hpp"
#include "ctk/plan/edge_tangency.hpp"
#include "ctk/plan/plan_trajectory.hpp"
#include "ctk/plan/planner_picture.hpp"
#include "ctk/plan/view_planner.hpp"

namespace ctk {
namespace {

// 64^3 voxels of 1 mm; `mu(p)` in 1/mm at each voxel centre p (mm).
template <typename F>
Volume volume_of(F mu) {
  Volume v(VolumeLayout::centred({64, 64, 64}, Eigen::Vector3d::Constant(1.0)));
  for (int k = 0; k < 64; ++k)
    for (int j = 0; j < 64; ++j)
      for (int i = 0; i < 64; ++i) v.at(i, j, k) = static_cast<float>(mu(v.layout.centre_of(i, j, k)));
  return v;
}

// A smooth step (about a voxel wide), so voxel corners do not favour the grid's axes.
double step(double inside_mm) { return 1.0 / (1.0 + std::exp(-2.0 * inside_mm)); }

Volume plate() {  // 4 x 30 x 40 mm, normal along x
  return volume_of([](const Eigen::Vector3d& p) {
    return 0.07 * step(2 - std::abs(p.x())) * step(15 - std::abs(p.y())) * step(20 - std::abs(p.z()));
  });
}

const SampleRegion kRegion{30.0, 30.0};

// The mean demand of the directions within 3 deg of the plate's plane (x = 0), relative to all.
double in_plane_demand(const std::vector<double>& demand, const std::vector<Eigen::Vector3d>& directions) {
  double sum = 0;
  int n = 0;
  for (std::size_t d = 0; d < directions.size(); ++d)
    if (std::abs(directions[d].x()) < 0.05) sum += demand[d], ++n;
  return sum / n;
}

TEST(EdgeTangency, APlateWantsTheDirectionsInItsPlane) {
  const std::vector<Eigen::Vector3d> directions = HealpixSphere(8).directions();
  const std::vector<double> demand = tangent_edge_demand(plate(), kRegion, directions);
  ASSERT_EQ(demand.size(), directions.size());
  double mean = 0, in_plane = 0, along_normal = 0;
  int n_in = 0, n_normal = 0;
  for (std::size_t d = 0; d < directions.size(); ++d) {
    mean += demand[d] / static_cast<double>(directions.size());
    const double c = std::abs(directions[d].x());
    if (c < 0.05) in_plane += demand[d], ++n_in;
    if (c > 0.9) along_normal += demand[d], ++n_normal;
  }
  ASSERT_GT(n_in, 0);
  ASSERT_GT(n_normal, 0);
  EXPECT_NEAR(mean, 1.0, 1e-9);
  // The two large faces (30 x 40 mm) hold most of the squared gradient: the directions within
  // 3 deg of the plate's plane get several times the mean demand; along the normal only the
  // narrow rims are grazed.
  EXPECT_GT(in_plane / n_in, 3.0);
  EXPECT_LT(along_normal / n_normal, 0.5);
  // A narrower tangent width concentrates the demand further.
  EdgeTangencyOptions narrow;
  narrow.tangent_width_deg = 4;
  const std::vector<double> sharp = tangent_edge_demand(plate(), kRegion, directions, narrow);
  double sharp_in = 0;
  for (std::size_t d = 0; d < directions.size(); ++d)
    if (std::abs(directions[d].x()) < 0.05) sharp_in += sharp[d] / n_in;
  EXPECT_GT(sharp_in, in_plane / n_in);
}

TEST(EdgeTangency, ABallWantsEveryDirectionAlikeAndAUniformRegionNothing) {
  const std::vector<Eigen::Vector3d> directions = HealpixSphere(8).directions();
  const Volume ball = volume_of([](const Eigen::Vector3d& p) { return 0.03 * step(18 - p.norm()); });
  double least = 1e9, most = 0;
  for (double d : tangent_edge_demand(ball, kRegion, directions)) {
    least = std::min(least, d);
    most = std::max(most, d);
  }
  EXPECT_GT(least, 0.85);
  EXPECT_LT(most, 1.15);
  for (double d : tangent_edge_demand(volume_of([](const Eigen::Vector3d&) { return 0.02; }), kRegion, directions))
    EXPECT_EQ(d, 1.0);
  // Edges outside the region do not count: the plate moved 40 mm up leaves no demand.
  const Volume outside =
      volume_of([](const Eigen::Vector3d& p) { return std::abs(p.x()) < 2 && std::abs(p.z() - 26) < 5 ? 0.07 : 0.0; });
  for (double d : tangent_edge_demand(outside, SampleRegion{30.0, 15.0}, directions)) EXPECT_EQ(d, 1.0);
  EdgeTangencyOptions bad;
  bad.tangent_width_deg = 0;
  EXPECT_THROW(tangent_edge_demand(ball, kRegion, directions, bad), std::invalid_argument);
}

TEST(EdgeTangency, ThePlannerPutsMoreViewsInThePlatePlaneAndStaysSpread) {
  PlannerOptions o;
  o.planned_views = 60;
  o.seed = 3;
  auto in_band = [](const std::vector<Eigen::Vector3d>& views) {
    int n = 0;
    for (const Eigen::Vector3d& v : views) n += std::abs(v.x()) < std::sin(10 * M_PI / 180);
    return n;
  };
  auto plan = [&](double weight) {
    o.edge_tangency_weight = weight;
    ViewPlanner p(o);
    p.set_edge_demand(tangent_edge_demand(plate(), kRegion, p.candidates()));
    for (int i = 0; i < 60; ++i) p.record_acquired(*p.next());
    return p.acquired();
  };
  const std::vector<Eigen::Vector3d> even = plan(0.0), planned = plan(0.5);
  // The +-10 deg band is 17 % of the sphere: about 10 of 60 evenly spread views (9 here); the
  // plate's demand at the default weight puts 17 there (18 at 0.25, 22 at 0.75, 34 at 1).
  EXPECT_LE(in_band(even), 12);
  EXPECT_GE(in_band(planned), 15);
  // Still spread: no two views (as lines) closer than a quarter of the even spacing.
  const double g0 = std::sqrt(2 * M_PI / 60);
  for (std::size_t i = 0; i < planned.size(); ++i)
    for (std::size_t j = 0; j < i; ++j) EXPECT_GT(line_distance_rad(planned[i], planned[j]), g0 / 4);
  // A demand of 1 everywhere is the even spread, weight for weight.
  o.edge_tangency_weight = 0.5;
  ViewPlanner a(o), b(o);
  a.set_edge_demand(std::vector<double>(a.candidates().size(), 1.0));
  for (const Eigen::Vector3d& v : even) a.record_acquired(v), b.record_acquired(v);
  const auto wa = a.weights(), wb = b.weights();
  for (std::size_t c = 0; c < wa.size(); ++c) EXPECT_DOUBLE_EQ(wa[c].weight(), wb[c].weight());
}

TEST(EdgeTangency, PlanningOnAPictureOfThePlateReadsItsEdgesAndSkipsWhatIsOutOfReach) {
  PlanningOptions o;
  o.views = 60;
  o.planner.planned_views = 60;
  o.planner.seed = 3;
  o.segmentation.region = kRegion;
  o.coarse_volume = plate().layout;
  const auto reachable = [](const Eigen::Vector3d& d) { return std::abs(d.z()) < 0.9; };
  const auto in_band = [](const std::vector<Eigen::Vector3d>& views) {
    int n = 0;
    for (const Eigen::Vector3d& v : views) n += std::abs(v.x()) < std::sin(10 * M_PI / 180);
    return n;
  };
  const std::vector<Eigen::Vector3d> planned = plan_on_picture(plate(), o, {}, reachable);
  ASSERT_EQ(planned.size(), 60U);
  for (const Eigen::Vector3d& d : planned) EXPECT_LT(std::abs(d.z()), 0.9);
  // The scout comes first: the 20 of its 24 directions below the two polar rings (|z| = 0.92,
  // whose opposites are out of reach too), in its order.
  std::vector<Eigen::Vector3d> scout;
  for (const Eigen::Vector3d& d : scout_directions(2))
    if (reachable(d)) scout.push_back(d);
  ASSERT_EQ(scout.size(), 20U);
  for (std::size_t i = 0; i < scout.size(); ++i) EXPECT_TRUE(planned[i].isApprox(scout[i])) << i;
  // The plate's edges pull the 40 draws into its plane: 26 of 60 views in the +-10 deg band at
  // the default edge share (all the density following the edges; 19 at half) against 8 with none
  // (2 of them scout views).
  o.planner.edge_tangency_weight = 0;
  const std::vector<Eigen::Vector3d> even = plan_on_picture(plate(), o, {}, reachable);
  EXPECT_GE(in_band(planned), in_band(even) + 6);
  EXPECT_LE(in_band(even), 12);
  // The same seed and picture draw the same trajectory.
  const std::vector<Eigen::Vector3d> again = plan_on_picture(plate(), o, {}, reachable);
  ASSERT_EQ(again.size(), even.size());
  for (std::size_t i = 0; i < even.size(); ++i) EXPECT_TRUE(again[i].isApprox(even[i]));
}

TEST(EdgeTangency, ThePlannerReadsTheEdgesOfANoisyPictureAsThoseOfTheClean) {
  // Noise as in a coarse reconstruction (about half the holder wall's level: uniform, standard
  // deviation 0.01 /mm against the plate's 0.07 /mm; from a fixed hash, the same everywhere): its
  // gradients point every way and over the region outweigh the plate's faces, flattening the
  // demand. The planner reads its picture through a 3^3 median (picture_median.hpp), which leaves
  // the faces and far less of the noise.
  Volume noisy = plate();
  for (std::size_t v = 0; v < noisy.layout.voxel_count(); ++v) {
    const std::uint64_t h = (v + 1) * 0x9E3779B97F4A7C15ULL;
    const double u = static_cast<double>((h ^ (h >> 29)) % 1000003) / 1000003.0;  // [0, 1)
    noisy.data[v] += static_cast<float>(0.01 * std::sqrt(12.0) * (u - 0.5));
  }
  const std::vector<Eigen::Vector3d> directions = HealpixSphere(8).directions();
  const double clean = in_plane_demand(tangent_edge_demand(plate(), kRegion, directions), directions);
  PictureReading reading;
  reading.segmentation.region = kRegion;
  const double median = in_plane_demand(read_planner_picture(noisy, directions, reading, {}).edge_demand, directions);
  reading.median = false;
  const double raw = in_plane_demand(read_planner_picture(noisy, directions, reading, {}).edge_demand, directions);
  // Measured: in-plane demand 4.31 clean, 1.14 noisy, 2.60 noisy read through the median.
  EXPECT_GT(clean, 3.0);
  EXPECT_LT(raw, 0.3 * clean);
  EXPECT_GT(median, 0.55 * clean);
}

}  // namespace
}  // namespace ctk

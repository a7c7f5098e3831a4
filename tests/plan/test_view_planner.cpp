// The planner's parts against what they must find: the absorbers of a known volume (and none in
// a sample without contrast), the analytic path lengths through a plate from three directions,
// draws that avoid the plate's plane yet stay spread and reproducible, refusals that rule out
// only their neighbourhood, and a reconstruction that really continues where it stopped.
#include <gtest/gtest.h>

#include <cmath>

#include "ctk/geom/detector_binning.hpp"
#include "ctk/plan/absorber_segmentation.hpp"
#include "ctk/plan/direction_damage.hpp"
#include "ctk/plan/incremental_reconstruction.hpp"
#include "ctk/plan/view_planner.hpp"

namespace ctk {
namespace {

constexpr double kDegree = M_PI / 180.0;

// A 64^3 volume of 1 mm voxels: a plastic block, a 4 x 30 x 50 mm aluminium-like plate (normal
// along x) beside it, and the holder's POM wall (25 to 28 mm from the axis) with a sphere in it.
Volume plate_sample(bool with_plate, float block_mu = 0.015f) {
  Volume v(VolumeLayout::centred({64, 64, 64}, Eigen::Vector3d::Constant(1.0)));
  for (int k = 0; k < 64; ++k)
    for (int j = 0; j < 64; ++j)
      for (int i = 0; i < 64; ++i) {
        const Eigen::Vector3d p = v.layout.centre_of(i, j, k);
        float mu = 0;
        if (std::abs(p.x() + 6) < 10 && std::abs(p.y()) < 9 && std::abs(p.z()) < 15) mu = block_mu;
        if (with_plate && std::abs(p.x() - 13) < 2 && std::abs(p.y()) < 15 && std::abs(p.z()) < 25) mu = 0.07f;
        if (p.head<2>().norm() > 25 && p.head<2>().norm() < 28) mu = 0.027f;  // the wall
        if ((p - Eigen::Vector3d(0, 27.5, 3)).norm() < 1.5) mu = 0.075f;      // a sphere
        v.at(i, j, k) = mu;
      }
  return v;
}

TEST(AbsorberSegmentation, FindsThePlateAndIgnoresTheHolder) {
  const AbsorberSegmentation s = segment_absorbers(plate_sample(true));
  // 4 x 30 x 50 voxel centres inside the plate.
  EXPECT_EQ(s.voxels, 4u * 30u * 50u);
  EXPECT_NEAR(s.wall_level, 0.027, 1e-6);
  const Volume& m = s.absorbers;
  EXPECT_EQ(m.at(32 + 13, 32, 32), 1.0f);
  EXPECT_EQ(m.at(32 - 6, 32, 32), 0.0f);
  EXPECT_EQ(m.at(32, 32 + 27, 35), 0.0f) << "the holder's sphere is blanked";

  const AbsorberSegmentation none = segment_absorbers(plate_sample(false));
  EXPECT_EQ(none.voxels, 0u);
  EXPECT_NE(none.note.find("no absorbers"), std::string::npos) << none.note;
  // A denser plastic (PVC-like, 1.7 times the wall) is not an absorber either.
  EXPECT_EQ(segment_absorbers(plate_sample(false, 0.046f)).voxels, 0u);
}

TEST(DirectionDamage, LongestPathsThroughAPlateMatchItsEdges) {
  const AbsorberSegmentation s = segment_absorbers(plate_sample(true));
  const std::vector<DirectionDamage> d = direction_damage(
      s, {Eigen::Vector3d::UnitX(), Eigen::Vector3d::UnitY(), Eigen::Vector3d::UnitZ(), Eigen::Vector3d(1, 0, 1).normalized()});
  // Cone-beam rays cross the plate almost along the axis: the path is its edge (within a voxel).
  EXPECT_NEAR(d[0].longest_path_mm, 4.0, 1.0);
  EXPECT_NEAR(d[1].longest_path_mm, 30.0, 1.5);
  EXPECT_NEAR(d[2].longest_path_mm, 50.0, 2.0);
  EXPECT_NEAR(d[3].longest_path_mm, 4.0 * std::sqrt(2.0), 1.5);
  // The shadow along the plate's normal is the largest face, 30 x 50 mm.
  EXPECT_GT(d[0].shadow_fraction, d[2].shadow_fraction);
  // Nothing segmented: nothing is damaged.
  for (const DirectionDamage& x : direction_damage(segment_absorbers(plate_sample(false)), {Eigen::Vector3d::UnitX()}))
    EXPECT_EQ(x.longest_path_mm, 0.0);
}

// Damage of a plate with normal x, analytically: its thickness over |cos| of the angle to the
// normal, capped by its extent.
std::vector<double> plate_damage(const std::vector<Eigen::Vector3d>& candidates) {
  std::vector<double> d;
  for (const Eigen::Vector3d& c : candidates) d.push_back(std::min(50.0, 4.0 / std::max(1e-3, std::abs(c.x()))));
  return d;
}

std::vector<Eigen::Vector3d> draw(ViewPlanner& planner, int count) {
  std::vector<Eigen::Vector3d> chosen;
  for (int i = 0; i < count; ++i) {
    const auto next = planner.next();
    if (!next) break;
    planner.record_acquired(*next);
    chosen.push_back(*next);
  }
  return chosen;
}

TEST(ViewPlanner, AvoidsThePlatePlaneStaysSpreadAndIsReproducible) {
  PlannerOptions o;
  o.damage_exponent = 2.0;    // the mechanism at a strength that shows over 40 draws (the default is milder)
  o.widest_gap_fraction = 0;  // every gap open to the damage's choice
  o.planned_views = 60;
  o.seed = 5;
  ViewPlanner a(o);
  a.set_damage(plate_damage(a.candidates()));
  const std::vector<Eigen::Vector3d> chosen = draw(a, 40);
  ASSERT_EQ(chosen.size(), 40u);
  double mean_cos = 0;
  int in_plane = 0;
  for (const auto& c : chosen) {
    mean_cos += std::abs(c.x()) / 40;
    in_plane += std::abs(c.x()) < 0.2;  // paths of 20 mm and more
  }
  // Uniform directions give 0.5 (+- 0.05 over 40 draws) and 20 % within the plate's plane band.
  EXPECT_GT(mean_cos, 0.6);
  EXPECT_LE(in_plane, 2);
  // Spread: no two views (or a view and another's opposite) closer than a third of the spacing.
  const double g0 = std::sqrt(2 * M_PI / 60);
  for (std::size_t i = 0; i < chosen.size(); ++i)
    for (std::size_t j = 0; j < i; ++j) EXPECT_GT(line_distance_rad(chosen[i], chosen[j]), g0 / 3);

  ViewPlanner b(o);
  b.set_damage(plate_damage(b.candidates()));
  const std::vector<Eigen::Vector3d> again = draw(b, 40);
  for (std::size_t i = 0; i < chosen.size(); ++i) EXPECT_EQ(chosen[i], again[i]);
  o.seed = 6;
  ViewPlanner c(o);
  c.set_damage(plate_damage(c.candidates()));
  EXPECT_NE(draw(c, 5).front(), chosen.front());

  // Without absorbers the damage term is neutral: draws cover both the plane and the normal.
  ViewPlanner free_planner(PlannerOptions{});
  double free_cos = 0;
  for (const auto& d : draw(free_planner, 40)) free_cos += std::abs(d.x()) / 40;
  EXPECT_NEAR(free_cos, 0.5, 0.12);
}

// The largest distance (as a line) from a candidate to its nearest chosen view.
double widest_gap(const std::vector<Eigen::Vector3d>& candidates, const std::vector<Eigen::Vector3d>& chosen) {
  double widest = 0;
  for (const Eigen::Vector3d& c : candidates) {
    double nearest = M_PI;
    for (const Eigen::Vector3d& a : chosen) nearest = std::min(nearest, line_distance_rad(c, a));
    widest = std::max(widest, nearest);
  }
  return widest;
}

// The widest gap 60 draws without absorbers leave, drawing only where the gap is at least f
// times the widest.
double widest_gap_after_60_draws(std::uint64_t seed, double f) {
  PlannerOptions o;
  o.planned_views = 60;
  o.seed = seed;
  o.widest_gap_fraction = f;
  ViewPlanner p(o);
  return widest_gap(p.candidates(), draw(p, 60));
}

// With no absorber the draws must cover the sphere about as evenly as the whole-sphere order: no
// candidate farther than 0.31 rad (as a line) from one of 60 views. Seeds 1 to 8 give 0.27 to 0.30
// at the default spread exponent (4) and 0.31 to 0.38 with the plain spread term (1), drawing
// anywhere (f = 0: the spread term alone).
TEST(ViewPlanner, WithoutAbsorbersTheDrawsLeaveNoWideGap) {
  for (std::uint64_t seed : {1, 2, 3}) EXPECT_LT(widest_gap_after_60_draws(seed, 0), 0.31) << "seed " << seed;
}

// Drawing only among the wider gaps spreads the views more evenly: seeds 1 to 3 leave 0.273 to
// 0.279 rad at the default (f = 0.5) and 0.257 to 0.266 at f = 0.9, where drawing anywhere
// (f = 0) leaves 0.278 to 0.292; at each seed the default leaves less than f = 0.
TEST(ViewPlanner, DrawsAmongTheWidestGapsLeaveSmallerGaps) {
  for (std::uint64_t seed : {1, 2, 3}) {
    const double by_default = widest_gap_after_60_draws(seed, PlannerOptions{}.widest_gap_fraction);
    EXPECT_LT(by_default, widest_gap_after_60_draws(seed, 0)) << "seed " << seed;
    EXPECT_LT(by_default, 0.285) << "seed " << seed;
    EXPECT_LT(widest_gap_after_60_draws(seed, 0.9), 0.27) << "seed " << seed;
  }
}

TEST(ViewPlanner, ARefusalRulesOutItsNeighbourhoodOnly) {
  ViewPlanner p(PlannerOptions{});
  const Eigen::Vector3d refused = p.candidates()[300];
  p.record_unreachable(refused);
  const std::vector<CandidateWeight> w = p.weights();
  int ruled_out = 0;
  for (std::size_t c = 0; c < w.size(); ++c) {
    const double angle = std::acos(std::min(1.0, p.candidates()[c].dot(refused)));
    if (w[c].reach == 0) {
      ++ruled_out;
      EXPECT_LE(angle, 4.0 * kDegree);
    } else if (angle < 10 * kDegree) {
      EXPECT_GT(w[c].weight(), 0) << "a neighbour of a refused direction stays a candidate";
    }
  }
  EXPECT_EQ(ruled_out, 1);
}

TEST(IncrementalReconstruction, EachUpdateContinuesWhereTheLastStopped) {
  const Volume truth = plate_sample(true);
  const Detector detector{96, 96, 2.0, 2.0};
  const Intrinsics K = Intrinsics::from_setup(1500, detector, detector.centre_px());
  IncrementalOptions o;
  o.binning = 2;
  o.first_update_iterations = 4;
  o.iterations_per_update = 4;
  IncrementalReconstruction recon(truth.layout, detector, o);
  JosephProjector A;
  std::vector<ProjectionMatrix> coarse_views;
  ProjectionStack coarse_b(0, 48, 48);
  auto add = [&](int v) {
    const ProjectionMatrix P = virtual_view(Eigen::Vector3d(std::cos(0.5 * v), std::sin(0.5 * v), 0.3 * std::sin(v)), K, 1000);
    ProjectionStack y(1, detector.rows, detector.cols);
    A.forward(truth, {P}, y);
    const Image image{detector.cols, detector.rows, std::vector<float>(y.data.begin(), y.data.end())};
    recon.add_view(P, image, Image{});
    coarse_views.push_back(binned_matrix(P, 2));
    const Image binned = binned_image(image, 2);
    coarse_b.views += 1;
    coarse_b.data.insert(coarse_b.data.end(), binned.pixels.begin(), binned.pixels.end());
  };
  for (int v = 0; v < 12; ++v) add(v);
  const SolverReport first = recon.update();
  const SolverReport second = recon.update();
  EXPECT_NEAR(second.iterations.front().cost, first.iterations.back().cost, 1e-6 * first.iterations.back().cost);
  EXPECT_LT(second.iterations.back().cost, 0.9 * first.iterations.back().cost);
  EXPECT_EQ(recon.coarse_detector().cols, 48);

  // Views added after updates: the cost the next update starts from (from the residual it keeps)
  // is the cost of the volume so far over all the views, found here by projecting it afresh.
  for (int v = 12; v < 16; ++v) add(v);
  const Volume before = recon.volume();
  ProjectionStack Ax(coarse_b.views, 48, 48);
  A.forward(before, coarse_views, Ax);
  double data_term = 0;
  for (std::size_t i = 0; i < Ax.data.size(); ++i) data_term += 0.5 * std::pow(double(Ax.data[i]) - coarse_b.data[i], 2);
  const double cost = data_term + o.lambda * regulariser_value(Regulariser::gradient, before);
  const SolverReport third = recon.update();
  EXPECT_NEAR(third.iterations.front().cost, cost, 1e-4 * cost);
  EXPECT_GT(third.iterations.front().cost, 1.5 * second.iterations.back().cost);  // the new views are not fitted yet
  EXPECT_LT(third.iterations.back().cost, 0.9 * third.iterations.front().cost);
}

}  // namespace
}  // namespace ctk

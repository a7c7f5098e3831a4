// How the fast projector deals views' lines into tables (libproj/src/slab_lines.hpp): every
// line once, circular views as they come, spherical views so that neighbours share slabs.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "ctk/proj/ray_geometry.hpp"
#include "ctk/proj/standard_problem.hpp"
#include "slab_lines.hpp"

namespace ctk {
namespace {

struct Dealt {
  StandardProblem problem;
  std::vector<ViewRays> rays;
  std::vector<detail::LanePath> paths;
  detail::SlabLines dealt;
  Dealt(StandardTrajectory trajectory, int views, int rows_per_block) : problem(standard_problem(trajectory, views, 4)) {
    for (const ProjectionMatrix& P : problem.views) {
      rays.push_back(view_rays(P, problem.layout));
      paths.push_back(detail::LanePath::for_view(rays.back(), problem.layout, problem.cols, problem.rows));
    }
    dealt = detail::slab_lines(rays, paths, problem.layout, rows_per_block);
  }
};

// The dominant axis of view v's central ray, which its lane path is chosen for.
int central_axis(const Dealt& d, int v) { return d.paths[static_cast<std::size_t>(v)].axis; }

Eigen::Vector3d volume_centre(const Dealt& d) { return Eigen::Vector3d::Constant(0.5 * (d.problem.layout.size[0] - 1)); }

// The plane through view v's source and the volume's centre that holds its lanes' axis (x for
// rays along y or z, y for rays along x), as a unit normal.
Eigen::Vector3d central_plane_normal(const Dealt& d, int v) {
  const Eigen::Vector3d source = d.rays[static_cast<std::size_t>(v)].source;
  return Eigen::Vector3d::Unit(central_axis(d, v) == 0 ? 1 : 0).cross(volume_centre(d) - source).normalized();
}

// Mean angle (radians) between the central planes of consecutive views in each slab.
double mean_turn_within_slabs(const Dealt& d) {
  double sum = 0;
  int count = 0;
  for (const auto& slab : d.dealt.slabs)
    for (std::size_t i = 1; i < slab.size(); ++i) {
      const double c = std::abs(central_plane_normal(d, slab[i - 1].view).dot(central_plane_normal(d, slab[i].view)));
      sum += std::acos(std::min(1.0, c));
      ++count;
    }
  return count > 0 ? sum / count : 0.0;
}

TEST(SlabLines, EveryLineOfEveryViewIsInExactlyOneSlab) {
  for (const StandardTrajectory trajectory : {StandardTrajectory::circular, StandardTrajectory::spherical}) {
    const int rows_per_block = 8;
    const Dealt d(trajectory, 60, rows_per_block);
    std::vector<std::vector<int>> taken(d.paths.size());
    for (std::size_t v = 0; v < d.paths.size(); ++v) taken[v].assign(static_cast<std::size_t>(d.paths[v].lines), 0);
    int longest = 0;
    for (const auto& slab : d.dealt.slabs)
      for (const detail::LineRange& r : slab) {
        ASSERT_GE(r.line_begin, 0);
        ASSERT_GT(r.lines, 0);
        ASSERT_LE(r.line_begin + r.lines, d.paths[static_cast<std::size_t>(r.view)].lines);
        for (int line = r.line_begin; line < r.line_begin + r.lines; ++line)
          ++taken[static_cast<std::size_t>(r.view)][static_cast<std::size_t>(line)];
        longest = std::max(longest, r.lines);
      }
    for (std::size_t v = 0; v < taken.size(); ++v)
      for (std::size_t line = 0; line < taken[v].size(); ++line) EXPECT_EQ(taken[v][line], 1) << "view " << v << " line " << line;
    EXPECT_EQ(d.dealt.capacity, longest);
    // Views whose lines are further apart than the densest view's take fewer per slab, none more.
    EXPECT_LE(d.dealt.capacity, rows_per_block + 1);
  }
}

TEST(SlabLines, CircularViewsComeInTheirOrderWithTheSameLines) {
  const Dealt d(StandardTrajectory::circular, 60, 8);
  ASSERT_EQ(d.dealt.capacity, 8);
  for (std::size_t s = 0; s < d.dealt.slabs.size(); ++s) {
    const auto& slab = d.dealt.slabs[s];
    ASSERT_EQ(slab.size(), d.problem.views.size()) << "slab " << s;
    for (std::size_t i = 0; i < slab.size(); ++i) {
      EXPECT_EQ(slab[i].view, static_cast<int>(i));
      EXPECT_EQ(slab[i].line_begin, slab[0].line_begin);
      EXPECT_EQ(slab[i].lines, slab[0].lines);
    }
  }
}

TEST(SlabLines, SphericalViewsAreOrderedSoThatNeighboursShareSlabs) {
  const Dealt d(StandardTrajectory::spherical, 360, 24);
  // In the given order (random directions) consecutive views' central planes turn by 0.79 rad on
  // average (benchmarks/paired.py); in slab order, by about the spacing of 360 views over the sphere or less.
  const double turn = mean_turn_within_slabs(d);
  EXPECT_LT(turn, 0.1) << "mean turn " << turn << " rad";
  // The lines of one slab lie in it: for views along one axis (whose slabs are planes of one
  // family), each range's middle line's plane (through the source and the line's end pixels)
  // passes the centre at about the same signed distance as the others', within a slab's
  // thickness (24 lines of at most 1.07 voxels) of each other.
  double widest = 0;
  for (const auto& slab : d.dealt.slabs)
    for (int axis = 0; axis < 3; ++axis) {
      double lo = 1e300, hi = -1e300;
      for (const detail::LineRange& r : slab) {
        if (central_axis(d, r.view) != axis) continue;
        const ViewRays& rays = d.rays[static_cast<std::size_t>(r.view)];
        const detail::LanePath& path = d.paths[static_cast<std::size_t>(r.view)];
        const int line = r.line_begin + r.lines / 2;
        int u0, v0, u1, v1;
        path.pixel(line, 0, u0, v0);
        path.pixel(line, path.majors - 1, u1, v1);
        Eigen::Vector3d n = (rays.d0 + u0 * rays.du + v0 * rays.dv).cross(rays.d0 + u1 * rays.du + v1 * rays.dv).normalized();
        // Turned to the positive side of the axis the lines are stacked along (z, or y for rays along z).
        if (n[axis == 2 ? 1 : 2] < 0) n = -n;
        const double distance = n.dot(rays.source - volume_centre(d));
        lo = std::min(lo, distance), hi = std::max(hi, distance);
      }
      widest = std::max(widest, hi - lo);
    }
  EXPECT_LT(widest, 24 * 1.07 + 2.0);
}

}  // namespace
}  // namespace ctk

#include "slab_lines.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>

namespace ctk::detail {

namespace {

// A view's slabs: the plane through its source and the volume's centre that holds axis b (its
// lanes' axis), and where each of its lines' planes lies.
struct LinePlanes {
  int axis = 0;                                      // the central ray's dominant axis a
  Eigen::Vector3d normal = Eigen::Vector3d::Zero();  // of the central plane, on the positive side of c
  double tilt = 0;     // that normal's angle from axis c towards a (0 in circular trajectories about c)
  double heading = 0;  // the central ray's angle from a towards b: where the view looks within its slab
  Eigen::Vector3d direction = Eigen::Vector3d::Zero();  // the central ray's
  std::vector<double> offset;                           // per line: its plane's signed distance from the centre (voxels)
};

LinePlanes line_planes(const ViewRays& rays, const LanePath& path, const VolumeLayout& layout) {
  LinePlanes p;
  const Eigen::Vector3d& centre_ray = path.central_ray;
  p.axis = path.axis;
  const int c = other_axes(p.axis)[1];
  const Eigen::Vector3d centre =
      0.5 * (Eigen::Vector3d(layout.size[0], layout.size[1], layout.size[2]) - Eigen::Vector3d::Ones());
  const auto ray = [&](double major, double minor) {
    return path.along_u ? Eigen::Vector3d(rays.d0 + major * rays.du + minor * rays.dv)
                        : Eigen::Vector3d(rays.d0 + minor * rays.du + major * rays.dv);
  };
  // Turned to the positive side of c, the axis the lines are stacked along: |tilt| <= 45 degrees
  // (c's component is the ray's along a), so views along one axis turn their normals alike.
  p.normal = Eigen::Vector3d::Unit(other_axes(p.axis)[0]).cross(centre - rays.source).normalized();
  if (p.normal[c] < 0) p.normal = -p.normal;
  p.tilt = std::atan2(p.normal[p.axis], p.normal[c]);
  p.heading = std::atan2(centre_ray[other_axes(p.axis)[0]], centre_ray[p.axis]);
  p.direction = centre_ray.normalized();
  // Line j's plane: through the source and the line's first and last pixels (the staircase
  // unrounded), its normal on the side of the view's.
  const double m0 = path.major_first, m1 = path.major_first + std::max(path.majors - 1, 1);
  const auto normal = [&](int line) {
    const double minor = path.line_first + line;
    const Eigen::Vector3d n = ray(m0, minor + m0 * path.slope).cross(ray(m1, minor + m1 * path.slope)).normalized();
    return n.dot(p.normal) < 0 ? Eigen::Vector3d(-n) : n;
  };
  for (int line = 0; line < path.lines; ++line) p.offset.push_back(normal(line).dot(rays.source - centre));
  return p;
}

constexpr double kSameTilt = 1e-3;  // radians

// The views by dominant axis, then tilt, then heading; or as given where that is as coherent:
// circular trajectories, whose views share their slabs whatever the axis, are best taken in
// their order of heading across axes (sorted by axis, each axis's views come in two arcs, and a
// table spanning the jump between them measured 1.03-1.07x slower, benchmarks/paired.py). Coherence is
// the path length of the slabs' normals from view to view, plus a hundredth of the central rays'.
std::vector<int> slab_order(const std::vector<LinePlanes>& planes) {
  std::vector<int> given(planes.size());
  std::iota(given.begin(), given.end(), 0);
  std::vector<int> sorted = given;
  std::stable_sort(sorted.begin(), sorted.end(), [&](int p, int q) {
    const LinePlanes &a = planes[static_cast<std::size_t>(p)], &b = planes[static_cast<std::size_t>(q)];
    if (a.axis != b.axis) return a.axis < b.axis;
    // Tilts equal but for rounding (circular trajectories) are one tilt: the heading orders them.
    const double ta = std::round(a.tilt / kSameTilt), tb = std::round(b.tilt / kSameTilt);
    return ta != tb ? ta < tb : a.heading < b.heading;
  });
  const auto path_length = [&](const std::vector<int>& order) {
    double length = 0;
    const LinePlanes* last = nullptr;
    for (const int v : order) {
      const LinePlanes& p = planes[static_cast<std::size_t>(v)];
      if (p.offset.empty()) continue;  // in no slab
      // Planes, whichever way their normals turn.
      if (last)
        length += std::min((p.normal - last->normal).norm(), (p.normal + last->normal).norm()) +
                  0.01 * (p.direction - last->direction).norm();
      last = &p;
    }
    return length;
  };
  return path_length(sorted) < path_length(given) ? sorted : given;
}

}  // namespace

SlabLines slab_lines(const std::vector<ViewRays>& rays, const std::vector<LanePath>& paths, const VolumeLayout& layout,
                     int rows_per_block) {
  std::vector<LinePlanes> planes;
  std::vector<double> steps;                // each view's mean step between lines
  double lowest = 1e300, highest = -1e300;  // the outermost lines
  double lines = 0;                         // of every view
  for (std::size_t v = 0; v < rays.size(); ++v) {
    planes.push_back(paths[v].lines > 0 ? line_planes(rays[v], paths[v], layout) : LinePlanes{});
    const std::vector<double>& o = planes.back().offset;
    if (o.empty()) continue;
    lowest = std::min({lowest, o.front(), o.back()});
    highest = std::max({highest, o.front(), o.back()});
    lines += static_cast<double>(o.size());
    const double step = o.size() > 1 ? std::abs(o.back() - o.front()) / static_cast<double>(o.size() - 1) : 0.0;
    if (std::isfinite(step) && step > 0) steps.push_back(step);
  }
  SlabLines result;
  if (lines == 0) return result;
  // Slabs as thick as rows_per_block lines of the view with the densest lines, so that no view
  // has many more in one; but no thinner than half the median view's (a view whose lines barely
  // move must not make a slab per line of every other).
  double finest = 0;
  if (!steps.empty()) {
    const auto middle = steps.begin() + static_cast<std::ptrdiff_t>(steps.size() / 2);
    std::nth_element(steps.begin(), middle, steps.end());
    finest = std::max(*std::min_element(steps.begin(), steps.end()), 0.5 * *middle);
  }
  const std::vector<int> order = slab_order(planes);
  // No more slabs than lines (views whose lines lie far apart, or none apart: one slab).
  const double thickness = std::max(finest > 0 ? rows_per_block * finest : 1e300, (highest - lowest) / lines);
  // Slab edges half the finest step past a line of the lowest view: lines at the same steps
  // (every view of a circular trajectory) then fall rows_per_block to a slab, not one more
  // where rounding puts a line on an edge.
  const auto slab_of = [&](double offset) {
    return static_cast<std::size_t>(std::max(0.0, std::floor((offset - lowest + 0.5 * finest) / thickness)));
  };
  for (const int v : order) {
    const std::vector<double>& o = planes[static_cast<std::size_t>(v)].offset;
    for (std::size_t line = 0; line < o.size();) {
      const std::size_t slab = slab_of(o[line]);
      std::size_t end = line + 1;
      while (end < o.size() && slab_of(o[end]) == slab) ++end;
      if (result.slabs.size() <= slab) result.slabs.resize(slab + 1);
      result.slabs[slab].push_back({v, static_cast<int>(line), static_cast<int>(end - line)});
      result.capacity = std::max(result.capacity, static_cast<int>(end - line));
      line = end;
    }
  }
  return result;
}

}  // namespace ctk::detail

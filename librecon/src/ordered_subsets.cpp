#include "ctk/recon/ordered_subsets.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace ctk {

namespace {

// The angle between two lines through the origin, in radians, by its cosine's magnitude (cheap
// and monotone: a larger value is a smaller angle).
double line_closeness(const Eigen::Vector3d& a, const Eigen::Vector3d& b) { return std::abs(a.dot(b)); }

std::vector<Eigen::Vector3d> unit(const std::vector<Eigen::Vector3d>& directions) {
  std::vector<Eigen::Vector3d> u;
  u.reserve(directions.size());
  for (std::size_t i = 0; i < directions.size(); ++i) {
    const double n = directions[i].norm();
    if (!(n > 0) || !std::isfinite(n))
      throw std::invalid_argument("ordered_subsets: view " + std::to_string(i) + " has no direction (zero or not finite)");
    u.push_back(directions[i] / n);
  }
  return u;
}

}  // namespace

std::vector<std::vector<int>> ordered_subsets(const std::vector<Eigen::Vector3d>& directions, int count) {
  const int n = static_cast<int>(directions.size());
  if (count < 1) throw std::invalid_argument("ordered_subsets: count must be at least 1, got " + std::to_string(count));
  count = std::min(count, std::max(n, 1));
  const std::vector<Eigen::Vector3d> d = unit(directions);
  const auto at = [](int i) { return static_cast<std::size_t>(i); };
  std::vector<char> taken(at(n), 0);
  // closeness[j * n + i]: how close view i is (as a line) to the nearest member of subset j.
  std::vector<double> closeness(at(count) * at(n), -1.0);
  // The first member of each subset: farthest-point order over the whole scan, so that the
  // subsets start from directions spread over it.
  std::vector<double> nearest_first(at(n), -1.0);
  std::vector<std::vector<int>> subsets(at(count));
  const auto take = [&](int j, int view) {
    subsets[at(j)].push_back(view);
    taken[at(view)] = 1;
    for (int i = 0; i < n; ++i) {
      double& c = closeness[at(j) * at(n) + at(i)];
      c = std::max(c, line_closeness(d[at(i)], d[at(view)]));
    }
  };
  int next = 0;
  for (int j = 0; j < count; ++j) {
    take(j, next);
    int farthest = -1;
    double least = std::numeric_limits<double>::infinity();
    for (int i = 0; i < n; ++i) {
      if (taken[at(i)]) continue;
      double& c = nearest_first[at(i)];
      c = std::max(c, line_closeness(d[at(i)], d[at(next)]));
      if (c < least) least = c, farthest = i;
    }
    next = farthest;
  }
  // Then in turn each subset takes the view left that is farthest from its own members: every
  // subset grows as spread as what is left allows.
  for (int k = count; k < n; ++k) {
    const int j = k % count;
    int farthest = -1;
    double least = std::numeric_limits<double>::infinity();
    for (int i = 0; i < n; ++i)
      if (!taken[at(i)] && closeness[at(j) * at(n) + at(i)] < least) least = closeness[at(j) * at(n) + at(i)], farthest = i;
    take(j, farthest);
  }
  return subsets;
}

std::vector<std::vector<int>> ordered_subsets(const std::vector<ProjectionMatrix>& views, int count,
                                              const Eigen::Vector3d& centre_mm) {
  std::vector<Eigen::Vector3d> directions;
  directions.reserve(views.size());
  for (const ProjectionMatrix& P : views) directions.push_back(P.source_position() - centre_mm);
  return ordered_subsets(directions, count);
}

double subset_coverage_gap_deg(const std::vector<Eigen::Vector3d>& directions, const std::vector<int>& subset) {
  const std::vector<Eigen::Vector3d> d = unit(directions);
  double worst = 1.0;  // the smallest closeness of a view to its nearest subset member
  for (const Eigen::Vector3d& v : d) {
    double best = 0;
    for (int s : subset) best = std::max(best, line_closeness(v, d.at(static_cast<std::size_t>(s))));
    worst = std::min(worst, best);
  }
  return std::acos(std::clamp(worst, 0.0, 1.0)) * 180.0 / M_PI;
}

}  // namespace ctk

#include "ctk/calib/sphere_matching.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace ctk {

std::vector<int> assign_min_cost(const Eigen::MatrixXd& input) {
  // Works on an n x m matrix with n <= m (transposed otherwise): rows are added one at a time,
  // each by a shortest augmenting path under dual potentials u (rows) and v (columns).
  const bool transposed = input.rows() > input.cols();
  const Eigen::MatrixXd cost = transposed ? Eigen::MatrixXd(input.transpose()) : input;
  const int n = static_cast<int>(cost.rows()), m = static_cast<int>(cost.cols());
  const double inf = std::numeric_limits<double>::infinity();
  std::vector<double> u(static_cast<std::size_t>(n + 1), 0), v(static_cast<std::size_t>(m + 1), 0);
  std::vector<int> row_of(static_cast<std::size_t>(m + 1), 0), way(static_cast<std::size_t>(m + 1), 0);  // 1-based rows; 0 = none
  for (int row = 1; row <= n; ++row) {
    row_of[0] = row;
    int col = 0;
    std::vector<double> best(static_cast<std::size_t>(m + 1), inf);
    std::vector<bool> used(static_cast<std::size_t>(m + 1), false);
    do {
      used[static_cast<std::size_t>(col)] = true;
      const int r = row_of[static_cast<std::size_t>(col)];
      double delta = inf;
      int next = 0;
      for (int j = 1; j <= m; ++j) {
        if (used[static_cast<std::size_t>(j)]) continue;
        const double reduced = cost(r - 1, j - 1) - u[static_cast<std::size_t>(r)] - v[static_cast<std::size_t>(j)];
        if (reduced < best[static_cast<std::size_t>(j)]) {
          best[static_cast<std::size_t>(j)] = reduced;
          way[static_cast<std::size_t>(j)] = col;
        }
        if (best[static_cast<std::size_t>(j)] < delta) {
          delta = best[static_cast<std::size_t>(j)];
          next = j;
        }
      }
      for (int j = 0; j <= m; ++j) {
        if (used[static_cast<std::size_t>(j)]) {
          u[static_cast<std::size_t>(row_of[static_cast<std::size_t>(j)])] += delta;
          v[static_cast<std::size_t>(j)] -= delta;
        } else {
          best[static_cast<std::size_t>(j)] -= delta;
        }
      }
      col = next;
    } while (row_of[static_cast<std::size_t>(col)] != 0);
    // Flip the augmenting path.
    do {
      const int previous = way[static_cast<std::size_t>(col)];
      row_of[static_cast<std::size_t>(col)] = row_of[static_cast<std::size_t>(previous)];
      col = previous;
    } while (col != 0);
  }
  std::vector<int> result(static_cast<std::size_t>(input.rows()), -1);
  for (int j = 1; j <= m; ++j) {
    const int r = row_of[static_cast<std::size_t>(j)];
    if (r == 0) continue;
    if (transposed)
      result[static_cast<std::size_t>(j - 1)] = r - 1;
    else
      result[static_cast<std::size_t>(r - 1)] = j - 1;
  }
  return result;
}

std::vector<Eigen::Vector2d> candidate_shifts(const std::vector<Eigen::Vector2d>& predicted, const std::vector<bool>& usable,
                                              const std::vector<SphereDetection>& detections, double search, int count) {
  const double bin = 2.0;
  const int half = static_cast<int>(std::ceil(search / bin));
  const int size = 2 * half + 1;
  std::vector<int> votes(static_cast<std::size_t>(size * size), 0);
  std::vector<Eigen::Vector2d> offsets;
  for (std::size_t k = 0; k < predicted.size(); ++k) {
    if (!usable[k]) continue;
    for (const auto& d : detections) {
      const Eigen::Vector2d o = d.uv - predicted[k];
      if (std::abs(o.x()) > search || std::abs(o.y()) > search) continue;
      offsets.push_back(o);
      ++votes[static_cast<std::size_t>((std::lround(o.y() / bin) + half) * size + std::lround(o.x() / bin) + half)];
    }
  }
  // Votes of a bin and its 8 neighbours; local maxima in that sum, best first.
  std::vector<std::pair<int, int>> peaks;  // (votes, bin)
  auto summed = [&](int x, int y) {
    int s = 0;
    for (int dy = -1; dy <= 1; ++dy)
      for (int dx = -1; dx <= 1; ++dx)
        if (x + dx >= 0 && y + dy >= 0 && x + dx < size && y + dy < size)
          s += votes[static_cast<std::size_t>((y + dy) * size + x + dx)];
    return s;
  };
  for (int y = 0; y < size; ++y)
    for (int x = 0; x < size; ++x) {
      const int s = summed(x, y);
      if (s == 0) continue;
      bool peak = true;
      for (int dy = -1; dy <= 1 && peak; ++dy)
        for (int dx = -1; dx <= 1 && peak; ++dx)
          if ((dx || dy) && x + dx >= 0 && y + dy >= 0 && x + dx < size && y + dy < size && summed(x + dx, y + dy) > s)
            peak = false;
      if (peak) peaks.push_back({s, y * size + x});
    }
  std::sort(peaks.begin(), peaks.end(), std::greater<>());
  std::vector<Eigen::Vector2d> shifts{Eigen::Vector2d::Zero()};
  for (const auto& [v, b] : peaks) {
    if (static_cast<int>(shifts.size()) >= count) break;
    const int bx = b % size, by = b / size;
    const Eigen::Vector2d centre((bx - half) * bin, (by - half) * bin);
    // Refine: mean of the offsets within two bins.
    Eigen::Vector2d sum(0, 0);
    int n = 0;
    for (const auto& o : offsets)
      if ((o - centre).norm() <= 2 * bin) {
        sum += o;
        ++n;
      }
    const Eigen::Vector2d shift = n > 0 ? Eigen::Vector2d(sum / n) : centre;
    if ((shift - shifts.front()).norm() > bin) shifts.push_back(shift);
  }
  return shifts;
}

std::vector<SphereMatch> match_spheres(const std::vector<Eigen::Vector2d>& predicted, const std::vector<bool>& usable,
                                       const std::vector<SphereDetection>& detections, const Eigen::Vector2d& shift,
                                       double gate_px) {
  std::vector<int> spheres;
  for (std::size_t k = 0; k < predicted.size(); ++k)
    if (usable[k]) spheres.push_back(static_cast<int>(k));
  std::vector<SphereMatch> matches;
  if (spheres.empty() || detections.empty()) return matches;
  // Pairs beyond the gate cost the same large amount, so they never displace a good pair.
  const double beyond = 10 * gate_px * gate_px;
  Eigen::MatrixXd cost(static_cast<Eigen::Index>(spheres.size()), static_cast<Eigen::Index>(detections.size()));
  for (std::size_t i = 0; i < spheres.size(); ++i)
    for (std::size_t j = 0; j < detections.size(); ++j) {
      const double d2 = (detections[j].uv - predicted[static_cast<std::size_t>(spheres[i])] - shift).squaredNorm();
      cost(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(j)) = std::min(d2, beyond);
    }
  const std::vector<int> pick = assign_min_cost(cost);
  for (std::size_t i = 0; i < spheres.size(); ++i) {
    const int j = pick[i];
    if (j < 0) continue;
    const double d =
        (detections[static_cast<std::size_t>(j)].uv - predicted[static_cast<std::size_t>(spheres[i])] - shift).norm();
    if (d <= gate_px) matches.push_back({spheres[i], j, d});
  }
  return matches;
}

}  // namespace ctk

#include "ctk/recon/detector_pattern.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>

namespace ctk {

DetectorPattern mean_pattern(const ProjectionStack& images, const std::vector<int>& views, int row_margin, bool by_column,
                             double sign) {
  DetectorPattern p;
  p.rows = images.rows;
  p.cols = images.cols;
  p.by_column = by_column;
  const std::size_t n = images.pixels_per_view();
  p.mean.assign(n, 0.0);
  p.standard_error.assign(n, std::numeric_limits<double>::infinity());
  p.used.assign(n, false);
  const int first = std::min(row_margin, (images.rows - 1) / 2), last = images.rows - first;  // a one-row detector keeps its row
  const auto cols = static_cast<std::size_t>(images.cols);
  const auto count = static_cast<double>(views.size());
  // Per view, the values the pattern is made of: pixels, or each column's mean down the used rows.
  auto value = [&](int v, std::size_t pixel) {
    const float* im = images.view(v);
    if (!by_column) return sign * im[pixel];
    const std::size_t c = pixel % cols;
    double s = 0;
    for (int row = first; row < last; ++row) s += im[static_cast<std::size_t>(row) * cols + c];
    return sign * s / (last - first);
  };
  for (int row = first; row < last; ++row)
    for (std::size_t c = 0; c < cols; ++c) {
      const std::size_t pixel = static_cast<std::size_t>(row) * cols + c;
      p.used[pixel] = true;
      if (by_column && row > first) {  // the column's values, computed on its first used row
        p.mean[pixel] = p.mean[pixel - cols];
        p.standard_error[pixel] = p.standard_error[pixel - cols];
        continue;
      }
      double s = 0, s2 = 0;
      for (int v : views) {
        const double x = value(v, pixel);
        s += x;
        s2 += x * x;
      }
      const double mean = s / count;
      p.mean[pixel] = mean;
      if (views.size() > 1) p.standard_error[pixel] = std::sqrt(std::max(s2 / count - mean * mean, 0.0) / (count - 1));
    }
  return p;
}

namespace {

// The profile at offset 0 from its values at offsets `k` (never 0): a least-squares parabola
// through them, refitted once without the point it fits worst when that one stands out (beyond
// three times the median misfit): one defective neighbour does not move it.
double parabola_at_zero(const std::vector<double>& k, const std::vector<double>& y) {
  auto fit = [&](std::size_t skip) {
    Eigen::Matrix3d A = Eigen::Matrix3d::Zero();
    Eigen::Vector3d r = Eigen::Vector3d::Zero();
    for (std::size_t i = 0; i < k.size(); ++i) {
      if (i == skip) continue;
      const Eigen::Vector3d a(1.0, k[i], k[i] * k[i]);
      A += a * a.transpose();
      r += a * y[i];
    }
    return Eigen::Vector3d(A.ldlt().solve(r));
  };
  const Eigen::Vector3d first = fit(k.size());
  std::vector<double> misfit(k.size());
  for (std::size_t i = 0; i < k.size(); ++i) misfit[i] = std::abs(y[i] - (first(0) + first(1) * k[i] + first(2) * k[i] * k[i]));
  const auto worst = static_cast<std::size_t>(std::max_element(misfit.begin(), misfit.end()) - misfit.begin());
  std::vector<double> sorted = misfit;
  std::nth_element(sorted.begin(), sorted.begin() + static_cast<std::ptrdiff_t>(sorted.size() / 2), sorted.end());
  if (k.size() > 4 && misfit[worst] > 3 * sorted[sorted.size() / 2]) return fit(worst)(0);
  return first(0);
}

}  // namespace

std::vector<float> fine_part(const DetectorPattern& p, int half_width) {
  std::vector<float> out(p.mean.size(), 0.0f);
  std::vector<double> k, y;
  for (int row = 0; row < p.rows; ++row)
    for (int c = 0; c < p.cols; ++c) {
      const std::size_t pixel = static_cast<std::size_t>(row) * static_cast<std::size_t>(p.cols) + static_cast<std::size_t>(c);
      if (!p.used[pixel]) continue;
      k.clear();
      y.clear();
      for (int d = -half_width; d <= half_width; ++d)
        if (d != 0 && c + d >= 0 && c + d < p.cols) {
          k.push_back(d);
          y.push_back(p.mean[pixel + static_cast<std::size_t>(c + d) - static_cast<std::size_t>(c)]);
        }
      if (k.size() < 4) continue;  // too near a narrow detector's end to tell a pixel from a curve
      out[pixel] = static_cast<float>(p.mean[pixel] - parabola_at_zero(k, y));
    }
  return out;
}

double pattern_statistic(const DetectorPattern& p) {
  double total = 0;
  std::size_t n = 0;
  for (std::size_t i = 0; i < p.mean.size(); ++i) {
    if (!p.used[i] || !(p.standard_error[i] > 0) || std::isinf(p.standard_error[i])) continue;
    total += (p.mean[i] / p.standard_error[i]) * (p.mean[i] / p.standard_error[i]);
    ++n;
  }
  return n > 0 ? total / static_cast<double>(n) : 0.0;
}

}  // namespace ctk

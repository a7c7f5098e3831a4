#pragma once
// Small statistics shared by the libraries: the median (for an even count, the upper of the two
// middle values; 0 when there are none), the paired z-score that judges an effect on held-out
// views, a Wald statistic and its chi-square threshold, and the vertex of a least-squares
// parabola (where a scanned cost is least).
#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <vector>

namespace ctk {

/// The median of `values`, reordering them.
template <class T>
T median_in_place(std::vector<T>& values) {
  if (values.empty()) return T{};
  const auto middle = values.begin() + static_cast<std::ptrdiff_t>(values.size() / 2);
  std::nth_element(values.begin(), middle, values.end());
  return *middle;
}

/// The median of `values` (a copy; pass std::move when they are not needed afterwards).
template <class T>
T median(std::vector<T> values) {
  return median_in_place(values);
}

/// Mean of before - after over paired values (one per view) in standard errors of that mean:
/// how many standard errors `after` improves on `before`. When every difference is the same
/// (no spread) the answer is +-1e9 for a non-zero mean (finite, so reports stay valid JSON) and 0
/// otherwise; fewer than two pairs have no spread.
inline double paired_z(const std::vector<double>& before, const std::vector<double>& after) {
  const std::size_t n = std::min(before.size(), after.size());
  if (n == 0) return 0.0;
  double mean = 0;
  for (std::size_t i = 0; i < n; ++i) mean += before[i] - after[i];
  mean /= static_cast<double>(n);
  double var = 0;
  for (std::size_t i = 0; i < n; ++i) var += (before[i] - after[i] - mean) * (before[i] - after[i] - mean);
  var /= static_cast<double>(std::max<std::size_t>(n - 1, 1));
  const double se = std::sqrt(var / static_cast<double>(n));
  if (se > 0) return mean / se;
  return mean > 0 ? 1e9 : mean < 0 ? -1e9 : 0.0;
}

/// The value a paired z-score over `pairs` pairs (paired_z) exceeds by chance with probability
/// `level` when the true mean difference is zero: the one-sided quantile of Student's t with
/// pairs - 1 degrees of freedom (the z-score is that t statistic). std::invalid_argument unless
/// 0 < level < 1 and pairs >= 2.
double one_sided_threshold(double level, std::size_t pairs);

/// The value a chi-square with `dof` degrees of freedom exceeds by chance with probability
/// `level`. std::invalid_argument unless 0 < level < 1 and dof >= 1.
double chi_square_threshold(double level, int dof);

/// A Wald statistic: how far `values` stand from zero for their `covariance`, summed over the
/// directions the covariance constrains (eigenvalues above 1e-10 of the largest; a gauge's free
/// directions carry no information and are left out), and how many those are.
struct WaldStatistic {
  double chi2 = 0;
  int dof = 0;
};
WaldStatistic wald_statistic(const Eigen::VectorXd& values, const Eigen::MatrixXd& covariance);

/// Vertex of the least-squares parabola through (x_i, y_i) (three or more points); NaN when it
/// opens downwards or is flat.
double parabola_vertex(const std::vector<double>& x, const std::vector<double>& y);

}  // namespace ctk

#include "ctk/core/statistics.hpp"

#include <Eigen/Dense>
#include <limits>

namespace ctk {

double parabola_vertex(const std::vector<double>& x, const std::vector<double>& y) {
  const double x0 = x[x.size() / 2];  // centred, for conditioning
  Eigen::MatrixXd A(static_cast<Eigen::Index>(x.size()), 3);
  Eigen::VectorXd b(static_cast<Eigen::Index>(x.size()));
  for (std::size_t i = 0; i < x.size(); ++i) {
    const double t = x[i] - x0;
    A.row(static_cast<Eigen::Index>(i)) << t * t, t, 1.0;
    b(static_cast<Eigen::Index>(i)) = y[i];
  }
  const Eigen::Vector3d c = A.colPivHouseholderQr().solve(b);
  if (!(c(0) > 0)) return std::numeric_limits<double>::quiet_NaN();
  return x0 - c(1) / (2 * c(0));
}

}  // namespace ctk

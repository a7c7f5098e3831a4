#include "ctk/core/statistics.hpp"

#include <Eigen/Dense>
#include <boost/math/distributions/chi_squared.hpp>
#include <boost/math/distributions/students_t.hpp>
#include <limits>
#include <stdexcept>

namespace ctk {

double one_sided_threshold(double level, std::size_t pairs) {
  if (!(level > 0 && level < 1) || pairs < 2)
    throw std::invalid_argument("one_sided_threshold: expected 0 < level < 1 and at least two pairs");
  const boost::math::students_t t(static_cast<double>(pairs - 1));
  return boost::math::quantile(boost::math::complement(t, level));
}

double chi_square_threshold(double level, int dof) {
  if (!(level > 0 && level < 1) || dof < 1)
    throw std::invalid_argument("chi_square_threshold: expected 0 < level < 1 and at least one degree of freedom");
  const boost::math::chi_squared chi2(static_cast<double>(dof));
  return boost::math::quantile(boost::math::complement(chi2, level));
}

WaldStatistic wald_statistic(const Eigen::VectorXd& values, const Eigen::MatrixXd& covariance) {
  WaldStatistic w;
  if (values.size() == 0 || covariance.rows() != values.size() || covariance.cols() != values.size()) return w;
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(covariance);
  const double largest = eig.eigenvalues().maxCoeff();
  if (!(largest > 0)) return w;
  const Eigen::VectorXd along = eig.eigenvectors().transpose() * values;
  for (Eigen::Index i = 0; i < along.size(); ++i)
    if (eig.eigenvalues()(i) > 1e-10 * largest) {
      w.chi2 += along(i) * along(i) / eig.eigenvalues()(i);
      ++w.dof;
    }
  return w;
}

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

// The globals' covariance by eliminating per-view blocks one at a time, against Ceres' dense SVD
// of the whole Jacobian, on a small problem with the shape of a scan's: per-view poses, globals
// every view shares, priors on some globals, and a gauge direction the data leave unfixed.
#include <ceres/ceres.h>
#include <ceres/normal_prior.h>
#include <gtest/gtest.h>

#include <array>
#include <random>
#include <vector>

#include "ctk/calib/marginal_covariance.hpp"

namespace ctk {
namespace {

// r = A_v p_v + B_v g + C_v h - y: nonlinear enough to be a real cost function, linear for
// the covariance (its Jacobian does not depend on the parameters).
struct ViewResidual {
  Eigen::Matrix<double, 5, 3> A;
  Eigen::Matrix<double, 5, 2> B;
  Eigen::Matrix<double, 5, 2> C;
  template <typename T>
  bool operator()(const T* p, const T* g, const T* h, T* r) const {
    for (int i = 0; i < 5; ++i) {
      r[i] = T(0);
      for (int j = 0; j < 3; ++j) r[i] += A(i, j) * p[j];
      for (int j = 0; j < 2; ++j) r[i] += B(i, j) * g[j] + C(i, j) * h[j];
    }
    return true;
  }
};

// One pose's first parameter tied to another's.
struct Tie {
  template <typename T>
  bool operator()(const T* a, const T* b, T* r) const {
    r[0] = a[0] - b[0];
    return true;
  }
};

struct Problem {
  std::vector<std::array<double, 3>> poses;
  std::array<double, 2> g{0.1, -0.2}, h{0.3, 0.0};
  ceres::Problem problem;
  explicit Problem(bool gauge) : poses(12) {
    std::mt19937_64 rng(5);
    std::normal_distribution<double> n(0, 1);
    for (auto& p : poses) {
      ViewResidual f;
      for (int i = 0; i < 5; ++i) {
        for (int j = 0; j < 3; ++j) f.A(i, j) = n(rng);
        for (int j = 0; j < 2; ++j) f.B(i, j) = n(rng), f.C(i, j) = n(rng);
        // With the gauge, h's second direction moves every view exactly as the pose's first does.
        if (gauge) f.C(i, 1) = f.A(i, 0);
      }
      problem.AddResidualBlock(new ceres::AutoDiffCostFunction<ViewResidual, 5, 3, 2, 2>(new ViewResidual(f)), nullptr, p.data(),
                               g.data(), h.data());
    }
    // A prior on g alone (a residual with no pose).
    ceres::Matrix A = ceres::Matrix::Identity(2, 2) * 3.0;
    problem.AddResidualBlock(new ceres::NormalPrior(A, ceres::Vector::Zero(2)), nullptr, g.data());
  }
};

Eigen::MatrixXd ceres_dense_svd(Problem& p) {
  ceres::Covariance::Options o;
  o.algorithm_type = ceres::DENSE_SVD;
  o.null_space_rank = -1;
  ceres::Covariance c(o);
  const std::vector<const double*> blocks{p.g.data(), p.h.data()};
  EXPECT_TRUE(c.Compute(blocks, &p.problem));
  Eigen::Matrix<double, 4, 4, Eigen::RowMajor> m;
  EXPECT_TRUE(c.GetCovarianceMatrixInTangentSpace(blocks, m.data()));
  return m;
}

TEST(MarginalCovariance, EqualsTheDenseSvdOfTheWholeProblemWhenEverythingIsFixed) {
  Problem p(false);
  std::vector<double*> views;
  for (auto& pose : p.poses) views.push_back(pose.data());
  Eigen::MatrixXd schur;
  ASSERT_TRUE(marginal_covariance(p.problem, views, {p.g.data(), p.h.data()}, schur));
  const Eigen::MatrixXd dense = ceres_dense_svd(p);
  ASSERT_EQ(schur.rows(), 4);
  EXPECT_LT((schur - dense).norm(), 1e-9 * dense.norm()) << schur << "\n\n" << dense;
  // Holding the poses at their optimum would understate it: the marginal is larger.
  EXPECT_GT(schur(2, 2), 0.0);
}

TEST(MarginalCovariance, LeavesAnUnfixedDirectionOutAndRefusesCoupledViews) {
  Problem p(true);
  std::vector<double*> views;
  for (auto& pose : p.poses) views.push_back(pose.data());
  Eigen::MatrixXd schur;
  ASSERT_TRUE(marginal_covariance(p.problem, views, {p.g.data(), p.h.data()}, schur));
  // h's second parameter trades exactly against every pose: no information, so no variance is
  // claimed for it; g, fixed by its prior and the data, keeps a finite covariance.
  EXPECT_NEAR(schur(3, 3), 0.0, 1e-9);
  EXPECT_GT(schur(0, 0), 0.0);
  EXPECT_TRUE(schur.allFinite());
  // A residual tying two views together cannot be eliminated view by view.
  p.problem.AddResidualBlock(new ceres::AutoDiffCostFunction<Tie, 1, 3, 3>(new Tie), nullptr, p.poses[0].data(),
                             p.poses[1].data());
  EXPECT_FALSE(marginal_covariance(p.problem, views, {p.g.data(), p.h.data()}, schur));
}

}  // namespace
}  // namespace ctk

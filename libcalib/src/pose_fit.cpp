#include "ctk/calib/pose_fit.hpp"

#include <ceres/ceres.h>
#include <ceres/rotation.h>

#include <cmath>

#include "small_problem.hpp"

namespace ctk {

namespace {

struct Reprojection {
  Eigen::Matrix3d K;
  Eigen::Vector3d X;
  Eigen::Vector2d uv;

  template <typename T>
  bool operator()(const T* q, const T* t, T* residual) const {
    const Eigen::Map<const Eigen::Quaternion<T>> rotation(q);
    const Eigen::Matrix<T, 3, 1> Xc = rotation * X.cast<T>() + Eigen::Map<const Eigen::Matrix<T, 3, 1>>(t);
    const Eigen::Matrix<T, 3, 1> p = K.cast<T>() * Xc;
    residual[0] = p(0) / p(2) - T(uv.x());
    residual[1] = p(1) / p(2) - T(uv.y());
    return true;
  }
};

}  // namespace

PoseFit fit_pose(const Eigen::Matrix3d& K, const Rigid& initial, const std::vector<Eigen::Vector3d>& X,
                 const std::vector<Eigen::Vector2d>& uv, double robust) {
  Eigen::Quaterniond q(initial.linear());
  q.normalize();
  Eigen::Vector3d t = initial.translation();
  ceres::Problem problem;
  for (std::size_t i = 0; i < X.size(); ++i)
    problem.AddResidualBlock(new ceres::AutoDiffCostFunction<Reprojection, 2, 4, 3>(new Reprojection{K, X[i], uv[i]}),
                             new ceres::CauchyLoss(robust), q.coeffs().data(), t.data());
  problem.SetManifold(q.coeffs().data(), new ceres::EigenQuaternionManifold);
  const ceres::Solver::Summary summary = solve_small_problem(problem, 50, 1e-12);

  PoseFit fit;
  fit.converged = summary.IsSolutionUsable();
  fit.T_camera_holder = make_rigid(q.normalized().toRotationMatrix(), t);
  double ss = 0;
  for (std::size_t i = 0; i < X.size(); ++i) {
    const Eigen::Vector3d p = K * (fit.T_camera_holder * X[i]);
    const double r = (p.head<2>() / p.z() - uv[i]).norm();
    fit.residual_px.push_back(r);
    ss += r * r;
  }
  fit.rms_px = X.empty() ? 0.0 : std::sqrt(ss / static_cast<double>(X.size()));

  // Covariance of the translation and rotation, scaled by the residual variance per coordinate.
  // Six unknowns: a dense decomposition. The default, SuiteSparse QR, took a quarter of a view's
  // calibration (ctk calibrate on 120 cap views, 88 -> 121 views/s on 2 cores, run alternately).
  ceres::Covariance::Options cov_options;
  cov_options.algorithm_type = ceres::DENSE_SVD;
  cov_options.num_threads = 1;
  ceres::Covariance covariance(cov_options);
  const std::vector<std::pair<const double*, const double*>> blocks = {{t.data(), t.data()},
                                                                       {q.coeffs().data(), q.coeffs().data()}};
  const int dof = 2 * static_cast<int>(X.size()) - 6;
  if (dof > 0 && covariance.Compute(blocks, &problem)) {
    const double variance = ss / dof;
    double ct[9], cq[9];
    covariance.GetCovarianceBlock(t.data(), t.data(), ct);
    covariance.GetCovarianceBlockInTangentSpace(q.coeffs().data(), q.coeffs().data(), cq);
    for (int a = 0; a < 3; ++a) fit.translation_sigma_mm[a] = std::sqrt(std::max(0.0, ct[4 * a] * variance));
    // Quaternion tangent: half-angles; a rotation of theta moves the tangent by theta / 2.
    for (int a = 0; a < 3; ++a)
      fit.rotation_sigma_deg = std::max(fit.rotation_sigma_deg, 2 * std::sqrt(std::max(0.0, cq[4 * a] * variance)) * 180 / M_PI);
  }
  return fit;
}

}  // namespace ctk

#include "ctk/calib/marginal_covariance.hpp"

#include <ceres/crs_matrix.h>

#include <Eigen/Eigenvalues>
#include <utility>

namespace ctk {

namespace {

// The pseudo-inverse of a symmetric positive semi-definite matrix, eigenvalues below `relative`
// of the largest taken as zero.
Eigen::MatrixXd pseudo_inverse(const Eigen::MatrixXd& A, double relative = 1e-14) {
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eigen(A);
  const Eigen::VectorXd& l = eigen.eigenvalues();
  const double largest = l.size() > 0 ? l.maxCoeff() : 0.0;
  Eigen::VectorXd inverse = Eigen::VectorXd::Zero(l.size());
  for (Eigen::Index i = 0; i < l.size(); ++i)
    if (largest > 0 && l[i] > relative * largest) inverse[i] = 1.0 / l[i];
  return eigen.eigenvectors() * inverse.asDiagonal() * eigen.eigenvectors().transpose();
}

}  // namespace

bool marginal_covariance(ceres::Problem& problem, const std::vector<double*>& per_view, const std::vector<const double*>& globals,
                         Eigen::MatrixXd& covariance) {
  ceres::Problem::EvaluateOptions options;
  std::vector<int> owner;  // per column: its per-view block, or -1 for a global column
  std::vector<int> first;  // per per-view block: its first column
  std::vector<int> width;
  for (double* block : per_view) {
    if (!problem.HasParameterBlock(block) || problem.IsParameterBlockConstant(block)) continue;
    first.push_back(static_cast<int>(owner.size()));
    width.push_back(problem.ParameterBlockTangentSize(block));
    owner.insert(owner.end(), static_cast<std::size_t>(width.back()), static_cast<int>(first.size()) - 1);
    options.parameter_blocks.push_back(block);
  }
  const int global_start = static_cast<int>(owner.size());
  for (const double* block : globals) {
    owner.insert(owner.end(), static_cast<std::size_t>(problem.ParameterBlockTangentSize(block)), -1);
    options.parameter_blocks.push_back(const_cast<double*>(block));  // Evaluate's list is non-const
  }
  const int G = static_cast<int>(owner.size()) - global_start;
  options.num_threads = 2;
  ceres::CRSMatrix J;
  if (!problem.Evaluate(options, nullptr, nullptr, nullptr, &J)) return false;

  // J'J block by block: each view's own block, its coupling to the globals, and the globals'.
  std::vector<Eigen::MatrixXd> own(first.size()), coupling(first.size());
  for (std::size_t b = 0; b < first.size(); ++b) {
    own[b] = Eigen::MatrixXd::Zero(width[b], width[b]);
    coupling[b] = Eigen::MatrixXd::Zero(width[b], G);
  }
  Eigen::MatrixXd global = Eigen::MatrixXd::Zero(G, G);
  std::vector<std::pair<int, double>> local, shared;  // a row's entries on a view's block, on the globals
  for (int r = 0; r < J.num_rows; ++r) {
    local.clear();
    shared.clear();
    int view = -1;
    for (int e = J.rows[static_cast<std::size_t>(r)]; e < J.rows[static_cast<std::size_t>(r) + 1]; ++e) {
      const int c = J.cols[static_cast<std::size_t>(e)];
      const double v = J.values[static_cast<std::size_t>(e)];
      if (v == 0) continue;
      const int o = owner[static_cast<std::size_t>(c)];
      if (o < 0) {
        shared.emplace_back(c - global_start, v);
      } else {
        if (view >= 0 && view != o) return false;
        view = o;
        local.emplace_back(c - first[static_cast<std::size_t>(o)], v);
      }
    }
    for (const auto& [i, a] : shared)
      for (const auto& [j, b] : shared) global(i, j) += a * b;
    if (view < 0) continue;
    Eigen::MatrixXd& H = own[static_cast<std::size_t>(view)];
    Eigen::MatrixXd& C = coupling[static_cast<std::size_t>(view)];
    for (const auto& [i, a] : local) {
      for (const auto& [j, b] : local) H(i, j) += a * b;
      for (const auto& [j, b] : shared) C(i, j) += a * b;
    }
  }
  // S = H_gg - sum over views of H_gv H_vv^+ H_vg: the globals' information with the views free.
  for (std::size_t b = 0; b < first.size(); ++b)
    global.noalias() -= coupling[b].transpose() * pseudo_inverse(own[b]) * coupling[b];
  covariance = pseudo_inverse(0.5 * (global + global.transpose()));
  return true;
}

}  // namespace ctk

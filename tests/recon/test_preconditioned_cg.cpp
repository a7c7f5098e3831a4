// WLS-CG preconditioned by the separable curvature D = A'WA1 + lambda c: the objective falls at
// every iteration and reaches the plain CG's minimum; the curvature is what its definition says
// (each voxel's sum of a_ij w_i sum_k a_ik, by a projection of ones); with Poisson weights behind
// a dense absorber (the rays through it keep a few per mille of their counts) it needs fewer
// iterations than plain CG.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "../test_support.hpp"
#include "ctk/geom/trajectory.hpp"
#include "ctk/proj/joseph_operator.hpp"
#include "ctk/recon/separable_curvature.hpp"
#include "ctk/recon/wls_cg.hpp"

namespace ctk {
namespace {

struct Problem {
  VolumeLayout layout = VolumeLayout::centred({28, 28, 20}, Eigen::Vector3d::Constant(1.0));
  Detector detector{36, 28, 1.5, 1.5};
  std::vector<ProjectionMatrix> views;
  ProjectionStack b, weights;
  Volume truth;

  // `absorber`: the attenuation (per mm) of a 6 x 6 x 8 mm block at the centre; Poisson weights
  // (the detected share of the open beam's counts).
  explicit Problem(double absorber) {
    const Intrinsics K = Intrinsics::from_setup(600, detector, detector.centre_px());
    for (const auto& R : circular_rotations(Eigen::Vector3d::UnitZ(), 40, 0.0, 2 * M_PI))
      views.push_back(ProjectionMatrix::compose(
          K, make_rigid(rotation_looking_along(R * Eigen::Vector3d::UnitX()), Eigen::Vector3d(0, 0, 400))));
    truth = Volume(layout);
    for (int k = 4; k < 16; ++k)
      for (int j = 6; j < 22; ++j)
        for (int i = 5; i < 23; ++i) truth.at(i, j, k) = 0.02f + 0.0015f * static_cast<float>((i * 7 + j * 3 + k) % 5);
    for (int k = 6; k < 14; ++k)
      for (int j = 11; j < 17; ++j)
        for (int i = 11; i < 17; ++i) truth.at(i, j, k) = static_cast<float>(absorber);
    b = ProjectionStack(static_cast<int>(views.size()), detector.rows, detector.cols);
    JosephProjector().forward(truth, views, b);
    std::mt19937_64 rng(3);
    std::normal_distribution<float> noise(0.0f, 0.01f);
    for (float& v : b.data) v += noise(rng);
    weights = b;
    for (float& w : weights.data) w = std::exp(-w);
  }
  JosephOperator projection() const { return {views, layout, detector.rows, detector.cols}; }
};

WlsOptions options(CgPreconditioner preconditioner, int iterations) {
  WlsOptions o;
  o.iterations = iterations;
  o.tolerance = 0;
  o.lambda = 2.0;
  o.regulariser = Regulariser::gradient;
  o.preconditioner = preconditioner;
  return o;
}

TEST(SeparableCurvature, IsTheWeightedProjectionOfOnesBackProjected) {
  const Problem p(0.3);
  const JosephOperator A = p.projection();
  const Volume D = separable_data_curvature(A, &p.weights);
  // From the definition, by the operator itself: A'(W (A 1)).
  Volume ones(p.layout);
  std::fill(ones.data.begin(), ones.data.end(), 1.0f);
  ProjectionStack A1;
  A.apply(ones, A1);
  for (std::size_t i = 0; i < A1.data.size(); ++i) A1.data[i] *= p.weights.data[i];
  Volume expected;
  A.apply_adjoint(A1, expected);
  double worst = 0, peak = 0;
  for (std::size_t i = 0; i < D.data.size(); ++i) {
    worst = std::max(worst, std::abs(double(D.data[i]) - expected.data[i]));
    peak = std::max(peak, double(expected.data[i]));
  }
  EXPECT_GT(peak, 0);
  EXPECT_LE(worst, 1e-6 * peak);
  // Summed subset by subset, the same.
  std::vector<std::vector<int>> subsets(3);
  for (int v = 0; v < p.b.views; ++v) subsets[static_cast<std::size_t>(v % 3)].push_back(v);
  const Volume by_subsets = separable_data_curvature(A, &p.weights, subsets);
  for (std::size_t i = 0; i < D.data.size(); ++i) ASSERT_NEAR(by_subsets.data[i], D.data[i], 1e-5 * peak);
  EXPECT_DOUBLE_EQ(separable_penalty_curvature(Regulariser::gradient, 2.0), 24.0);
  EXPECT_DOUBLE_EQ(separable_penalty_curvature(Regulariser::identity, 2.0), 2.0);
}

TEST(WlsCg, DiagonalPreconditionerLowersTheCostEveryIterationAndReachesTheSameMinimum) {
  const Problem p(0.3);
  const JosephOperator A = p.projection();
  Volume plain(p.layout), preconditioned(p.layout);
  const SolverReport r_plain = solve_wls_cg(A, p.b, &p.weights, plain, options(CgPreconditioner::none, 150));
  const SolverReport r = solve_wls_cg(A, p.b, &p.weights, preconditioned, options(CgPreconditioner::diagonal, 150));
  for (std::size_t k = 1; k < r.iterations.size(); ++k)
    EXPECT_LE(r.iterations[k].cost, r.iterations[k - 1].cost * (1 + 1e-7)) << "iteration " << k;
  const double minimum = r_plain.iterations.back().cost;
  EXPECT_NEAR(r.iterations.back().cost, minimum, 1e-5 * minimum);
  double worst = 0, peak = 0;
  for (std::size_t i = 0; i < plain.data.size(); ++i) {
    worst = std::max(worst, std::abs(double(plain.data[i]) - preconditioned.data[i]));
    peak = std::max(peak, std::abs(double(plain.data[i])));
  }
  EXPECT_LE(worst, 2e-3 * peak);
}

TEST(WlsCg, DiagonalPreconditionerNeedsFewerIterationsBehindADenseAbsorber) {
  // 0.8 /mm over 6 mm: the rays through the block keep under 1 % of their counts, so the normal
  // matrix is a hundred times weaker on the block's voxels than around it; D takes that out.
  const Problem p(0.8);
  const JosephOperator A = p.projection();
  Volume converged(p.layout);
  const double minimum = solve_wls_cg(A, p.b, &p.weights, converged, options(CgPreconditioner::none, 400)).iterations.back().cost;
  const auto iterations_to = [&](CgPreconditioner preconditioner, double excess) {
    Volume x(p.layout);
    const SolverReport r = solve_wls_cg(A, p.b, &p.weights, x, options(preconditioner, 120));
    for (const IterationLog& log : r.iterations)
      if (log.cost - minimum <= excess * (r.iterations.front().cost - minimum)) return log.iteration;
    return 1000;
  };
  const int plain = iterations_to(CgPreconditioner::none, 1e-4);
  const int preconditioned = iterations_to(CgPreconditioner::diagonal, 1e-4);
  std::cout << "to 1e-4 of the initial excess cost: plain CG " << plain << " iterations, preconditioned " << preconditioned
            << "\n";
  EXPECT_LE(preconditioned, 0.6 * plain);  // 15 against 39 iterations when written
}

}  // namespace
}  // namespace ctk

// The solvers on data from the analytic simulator (no inverse crime: exact line integrals of a
// continuous phantom, 2 x 2 rays per pixel): a modified Shepp-Logan at 64^3 from 180 views.
#include <gtest/gtest.h>

#include <random>

#include "ctk/geom/trajectory.hpp"
#include "ctk/measure/measurements.hpp"
#include "ctk/phantoms/builtin_phantoms.hpp"
#include "ctk/phantoms/detector_response.hpp"
#include "ctk/phantoms/render.hpp"
#include "ctk/proj/joseph_operator.hpp"
#include "ctk/recon/memory_plan.hpp"
#include "ctk/recon/sirt.hpp"
#include "ctk/recon/wls_cg.hpp"

namespace ctk {
namespace {

constexpr int kSize = 64;
constexpr double kVoxel = 0.75;  // 48 mm across; the phantom spans 44 mm
const Detector kDetector{96, 96, 1.1, 1.1};

struct SheppLoganScan {
  Phantom phantom;
  VolumeLayout layout = VolumeLayout::centred({kSize, kSize, kSize}, Eigen::Vector3d::Constant(kVoxel));
  std::vector<ProjectionMatrix> views;
  ProjectionStack exact;  // noise-free line integrals
  Volume truth;           // the phantom averaged over each voxel (2 x 2 x 2 points)

  SheppLoganScan(double attenuation_scale, int view_count) : phantom(shepp_logan_phantom(22.0, attenuation_scale)) {
    const Intrinsics K = Intrinsics::from_setup(1500, kDetector, kDetector.centre_px());
    for (const auto& R : circular_rotations(Eigen::Vector3d::UnitZ(), view_count, 0.0, 2 * M_PI))
      views.push_back(ProjectionMatrix::compose(
          K, make_rigid(rotation_looking_along(R * Eigen::Vector3d::UnitX()), Eigen::Vector3d(0, 0, 1000))));
    exact = ProjectionStack(static_cast<int>(views.size()), kDetector.rows, kDetector.cols);
#pragma omp parallel for schedule(dynamic)
    for (int v = 0; v < exact.views; ++v) {
      const Image im =
          render_line_integrals(phantom, views[static_cast<std::size_t>(v)], kDetector, {2, std::nullopt, std::nullopt});
      std::copy(im.pixels.begin(), im.pixels.end(), exact.view(v));
    }
    truth = Volume(layout);
    for (int k = 0; k < kSize; ++k)
      for (int j = 0; j < kSize; ++j)
        for (int i = 0; i < kSize; ++i) {
          double sum = 0;
          for (int s = 0; s < 8; ++s)
            sum += phantom.attenuation_at(layout.centre_of(i, j, k) +
                                          0.25 * kVoxel * Eigen::Vector3d(s & 1 ? 1 : -1, s & 2 ? 1 : -1, s & 4 ? 1 : -1));
          truth.at(i, j, k) = static_cast<float>(sum / 8);
        }
  }

  // RMSE over the voxels inside the phantom's outer ellipsoid.
  double rmse(const Volume& x) const {
    double sum = 0;
    int n = 0;
    for (int k = 0; k < kSize; ++k)
      for (int j = 0; j < kSize; ++j)
        for (int i = 0; i < kSize; ++i) {
          if (phantom.primitives[0].contains(layout.centre_of(i, j, k)) == false) continue;
          const double d = double(x.at(i, j, k)) - truth.at(i, j, k);
          sum += d * d;
          ++n;
        }
    return std::sqrt(sum / n);
  }
};

const SheppLoganScan& noise_free_scan() {
  static const SheppLoganScan scan(0.02, 180);
  return scan;
}

// The truth smoothed by a 3 x 3 x 3 box: what a reconstruction one voxel less sharp than the
// grid would look like. Its RMSE is the bound a 30-iteration reconstruction must beat.
double one_voxel_blur_rmse(const SheppLoganScan& s) {
  Volume blurred(s.layout);
  for (int k = 1; k + 1 < kSize; ++k)
    for (int j = 1; j + 1 < kSize; ++j)
      for (int i = 1; i + 1 < kSize; ++i) {
        double sum = 0;
        for (int c = -1; c <= 1; ++c)
          for (int b = -1; b <= 1; ++b)
            for (int a = -1; a <= 1; ++a) sum += s.truth.at(i + a, j + b, k + c);
        blurred.at(i, j, k) = static_cast<float>(sum / 27);
      }
  return s.rmse(blurred);
}

TEST(WlsCg, NoiseFreeSheppLoganBeatsAOneVoxelBlurOfTheTruthAndImprovesEveryIteration) {
  const SheppLoganScan& s = noise_free_scan();
  const JosephOperator A(s.views, s.layout, s.exact.rows, s.exact.cols);
  Volume x(s.layout);
  WlsOptions o;
  o.iterations = 30;
  o.tolerance = 0;
  // Exact data of a continuous object still disagree with any voxel model at the edges; without a
  // penalty CG starts fitting that disagreement after ~15 iterations (semi-convergence). A mild
  // gradient penalty makes the error fall at every iteration.
  o.lambda = 5.0;
  o.regulariser = Regulariser::gradient;
  std::vector<double> rmse;  // after each iteration: x is updated before the callback
  const SolverReport report = solve_wls_cg(A, s.exact, nullptr, x, o, [&](const IterationLog&) { rmse.push_back(s.rmse(x)); });
  ASSERT_EQ(report.iterations.size(), 31u);
  for (std::size_t i = 1; i < report.iterations.size(); ++i)
    EXPECT_LT(report.iterations[i].cost, report.iterations[i - 1].cost) << "iteration " << i;
  const double bound = one_voxel_blur_rmse(s);
  std::cout << "RMSE after 30 CG iterations " << rmse.back() << " /mm, one-voxel blur of the truth " << bound << " /mm\n";
  EXPECT_LT(rmse.back(), bound);
  for (std::size_t i = 1; i < rmse.size(); ++i) EXPECT_LT(rmse[i], rmse[i - 1]) << "iteration " << i;
}

TEST(WlsCg, StatisticalWeightsBeatUnitWeightsAndTikhonovLowersNoise) {
  static const SheppLoganScan s(0.08, 90);  // dense: transmission down to ~0.3
  const CountsModel model{2000, 100};
  std::mt19937_64 rng(5);
  ProjectionStack b(s.exact.views, s.exact.rows, s.exact.cols), w = b;
  const std::size_t per_view = s.exact.pixels_per_view();
  std::size_t clamped = 0;
  const Image flat{kDetector.cols, kDetector.rows, std::vector<float>(per_view, 2100.0f)};
  const Image dark{kDetector.cols, kDetector.rows, std::vector<float>(per_view, 100.0f)};
  for (int v = 0; v < b.views; ++v) {
    Image p{kDetector.cols, kDetector.rows, std::vector<float>(s.exact.view(v), s.exact.view(v) + per_view)};
    Image counts = expected_counts(p, model);
    draw_counts(counts, model, rng);
    counts_to_line_integrals(counts, flat, dark, b.view(v), w.view(v), clamped);
  }
  const JosephOperator A(s.views, s.layout, b.rows, b.cols);
  WlsOptions o;
  o.iterations = 15;
  o.tolerance = 0;
  Volume ls(s.layout), wls(s.layout), tikhonov(s.layout);
  solve_wls_cg(A, b, nullptr, ls, o);
  solve_wls_cg(A, b, &w, wls, o);
  WlsOptions regularised = o;
  regularised.lambda = 20.0;
  regularised.regulariser = Regulariser::identity;
  solve_wls_cg(A, b, &w, tikhonov, regularised);
  // Noise: spread inside the large uniform region around the centre (the phantom's brain matter).
  auto noise = [&](const Volume& x) {
    double sum = 0, sum2 = 0;
    int n = 0;
    for (int k = 28; k < 36; ++k)
      for (int j = 24; j < 30; ++j)
        for (int i = 28; i < 36; ++i) {
          sum += x.at(i, j, k);
          sum2 += double(x.at(i, j, k)) * x.at(i, j, k);
          ++n;
        }
    return std::sqrt(sum2 / n - (sum / n) * (sum / n));
  };
  std::cout << "RMSE LS " << s.rmse(ls) << ", WLS " << s.rmse(wls) << ", WLS + Tikhonov " << s.rmse(tikhonov) << "; noise "
            << noise(ls) << ", " << noise(wls) << ", " << noise(tikhonov) << "; clamped " << clamped << "\n";
  EXPECT_LT(s.rmse(wls), s.rmse(ls));
  EXPECT_LT(noise(tikhonov), 0.9 * noise(wls));
}

// A 12^3 volume of 2 mm voxels seen by `count` random views of 20 x 20 pixels, with random data
// and weights in [0.2, 1].
struct SmallProblem {
  VolumeLayout layout = VolumeLayout::centred({12, 12, 12}, Eigen::Vector3d::Constant(2.0));
  std::vector<ProjectionMatrix> views;
  ProjectionStack b, w;
};

SmallProblem small_random_problem(int count, std::uint64_t direction_seed, std::uint64_t value_seed) {
  SmallProblem p;
  const Detector d{20, 20, 2.0, 2.0};
  const Intrinsics K = Intrinsics::from_setup(1500, d, d.centre_px());
  for (const auto& dir : random_directions(count, direction_seed))
    p.views.push_back(ProjectionMatrix::compose(K, make_rigid(rotation_looking_along(dir), Eigen::Vector3d(0, 0, 1000))));
  std::mt19937_64 rng(value_seed);
  std::uniform_real_distribution<float> u(0.2f, 1.0f);
  p.b = ProjectionStack(count, 20, 20);
  p.w = ProjectionStack(count, 20, 20);
  for (auto& v : p.b.data) v = u(rng);
  for (auto& v : p.w.data) v = u(rng);
  return p;
}

TEST(WlsCg, TikhonovSolutionSatisfiesTheNormalEquations) {
  // Small problem, many iterations: the gradient (A'WA + lambda I) x - A'W b must vanish.
  const SmallProblem p = small_random_problem(15, 9, 2);
  const VolumeLayout& layout = p.layout;
  const std::vector<ProjectionMatrix>& views = p.views;
  const ProjectionStack &b = p.b, &w = p.w;
  const JosephOperator A(views, layout, b.rows, b.cols);
  Volume x(layout);
  WlsOptions o;
  o.iterations = 300;
  o.tolerance = 1e-5;
  o.lambda = 0.5;
  const SolverReport r = solve_wls_cg(A, b, &w, x, o);
  EXPECT_LT(r.iterations.back().relative_gradient, 1e-4) << r.stop_reason;
  // Independent check of the gradient at the solution.
  ProjectionStack Ax(15, 20, 20);
  A.apply(x, Ax);
  for (std::size_t i = 0; i < Ax.data.size(); ++i) Ax.data[i] = w.data[i] * (Ax.data[i] - b.data[i]);
  Volume g(layout), Awb(layout);
  A.apply_adjoint(Ax, g);
  ProjectionStack wb = b;
  for (std::size_t i = 0; i < wb.data.size(); ++i) wb.data[i] *= w.data[i];
  A.apply_adjoint(wb, Awb);
  double gnorm = 0, scale = 0;
  for (std::size_t i = 0; i < g.data.size(); ++i) {
    const double gi = g.data[i] + o.lambda * x.data[i];
    gnorm += gi * gi;
    scale += double(Awb.data[i]) * Awb.data[i];
  }
  EXPECT_LT(std::sqrt(gnorm / scale), 1e-3);
}

TEST(WlsCg, AKeptResidualAndASkippedLastGradientChangeNothingInX) {
  // 2 + 1 iterations twice: restarted from the volume alone (the residual found by projecting it),
  // and with the residual handed over and no gradient after the last iteration. The volumes must
  // agree, and the residual handed back must be A x - b.
  const SmallProblem p = small_random_problem(6, 4, 5);
  const VolumeLayout& layout = p.layout;
  const std::vector<ProjectionMatrix>& views = p.views;
  const ProjectionStack& b = p.b;
  const JosephOperator A(views, layout, b.rows, b.cols);
  WlsOptions o;
  o.tolerance = 0;
  o.lambda = 0.5;
  Volume restarted(layout), handed_over(layout);
  ProjectionStack residual = b;
  for (auto& v : residual.data) v = -v;  // A 0 - b
  o.iterations = 2;
  solve_wls_cg(A, b, nullptr, restarted, o);
  solve_wls_cg(A, b, nullptr, handed_over, residual, o);
  o.iterations = 1;
  solve_wls_cg(A, b, nullptr, restarted, o);
  o.gradient_after_last = false;
  const SolverReport last = solve_wls_cg(A, b, nullptr, handed_over, residual, o);
  EXPECT_EQ(last.iterations.size(), 2u);
  EXPECT_LT(last.iterations.back().cost, last.iterations.front().cost);

  double diff = 0, norm = 0;
  for (std::size_t i = 0; i < restarted.data.size(); ++i) {
    diff += std::pow(double(restarted.data[i]) - handed_over.data[i], 2);
    norm += std::pow(double(restarted.data[i]), 2);
  }
  EXPECT_LT(std::sqrt(diff / norm), 1e-5);
  ProjectionStack Ax(6, 20, 20);
  A.apply(handed_over, Ax);
  double r_err = 0, r_norm = 0;
  for (std::size_t i = 0; i < Ax.data.size(); ++i) {
    r_err += std::pow(double(Ax.data[i]) - b.data[i] - residual.data[i], 2);
    r_norm += std::pow(double(residual.data[i]), 2);
  }
  EXPECT_LT(std::sqrt(r_err / r_norm), 1e-5);
}

TEST(Sirt, ConvergesOnNoiseFreeData) {
  const SheppLoganScan& s = noise_free_scan();
  const JosephOperator A(s.views, s.layout, s.exact.rows, s.exact.cols);
  Volume x(s.layout);
  SirtOptions o;
  o.iterations = 40;
  const SolverReport r = solve_sirt(A, s.exact, x, o);
  EXPECT_LT(r.iterations.back().cost, 0.05 * r.iterations.front().cost);
  EXPECT_LT(s.rmse(x), 0.5 * s.rmse(Volume(s.layout)));
}

TEST(MemoryPlan, ThesisSizeFitsIn24GB) {
  // 720^3 volume, 900 views of 720 x 720, weighted CG.
  SolverShape weighted_cg;
  weighted_cg.weighted = true;
  const MemoryPlan plan =
      plan_memory(weighted_cg, VolumeLayout::centred({720, 720, 720}, Eigen::Vector3d::Constant(0.1)), 900, 720, 720);
  std::cout << "thesis size, WLS-CG: " << plan.describe() << "\n";
  EXPECT_LT(plan.total_bytes(), 24'000'000'000ull);
  EXPECT_EQ(plan.volume_bytes, 720ull * 720 * 720 * 4);
  EXPECT_EQ(plan.stack_bytes, 900ull * 720 * 720 * 4);
}

TEST(Preprocessing, CountsBecomeLineIntegralsAndWeightsWithClampsCounted) {
  const Image counts{4, 1, {1100.0f, 600.0f, 50.0f, 5000.0f}};
  const Image flat{4, 1, {2100.0f, 2100.0f, 2100.0f, 2100.0f}};
  const Image dark{4, 1, {100.0f, 100.0f, 100.0f, 100.0f}};
  float p[4], w[4];
  std::size_t clamped = 0;
  counts_to_line_integrals(counts, flat, dark, p, w, clamped);
  EXPECT_NEAR(p[0], std::log(2.0), 1e-6);
  EXPECT_NEAR(p[1], std::log(4.0), 1e-6);
  EXPECT_NEAR(w[0], 0.5, 1e-6);
  EXPECT_NEAR(w[1], 0.25, 1e-6);
  EXPECT_EQ(clamped, 2u);  // below dark, and a transmission of 2.45
  EXPECT_TRUE(std::isfinite(p[2]));
  EXPECT_GT(p[2], 7.0f);
  EXPECT_NEAR(p[3], -std::log(1.5), 1e-6);
}

}  // namespace
}  // namespace ctk

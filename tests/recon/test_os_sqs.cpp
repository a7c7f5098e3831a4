// Ordered subsets (OS-SQS) against WLS-CG on the same objective, on views that are not evenly
// spaced: a circular scan whose angles bunch towards its start (the angle of view k grows as
// (k / n)^1.8), exact line integrals of a continuous Shepp-Logan (2 x 2 rays per pixel).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

#include "../test_support.hpp"
#include "ctk/geom/trajectory.hpp"
#include "ctk/phantoms/builtin_phantoms.hpp"
#include "ctk/phantoms/render.hpp"
#include "ctk/proj/joseph_operator.hpp"
#include "ctk/recon/huber_penalty.hpp"
#include "ctk/recon/ordered_subsets.hpp"
#include "ctk/recon/os_sqs.hpp"
#include "ctk/recon/wls_cg.hpp"

namespace ctk {
namespace {

constexpr int kSize = 48;
constexpr double kVoxel = 1.0;
const Detector kDetector{72, 72, 1.4, 1.4};

std::vector<double> bunched_angles(int n) {
  std::vector<double> a;
  for (int k = 0; k < n; ++k) a.push_back(2 * M_PI * std::pow(double(k) / n, 1.8));
  return a;
}

// A circular scan at `angles` of the Shepp-Logan; `counts` > 0 adds Poisson noise for that many
// counts in the open beam (then `w` holds the detected counts relative to it).
struct CircularScan {
  Phantom phantom = shepp_logan_phantom(22.0, 0.02);
  VolumeLayout layout = VolumeLayout::centred({kSize, kSize, kSize}, Eigen::Vector3d::Constant(kVoxel));
  std::vector<ProjectionMatrix> views;
  ProjectionStack b;
  Volume truth;

  ProjectionStack w;

  CircularScan(const std::vector<double>& angles, double counts) {
    const int n = static_cast<int>(angles.size());
    const Intrinsics K = Intrinsics::from_setup(1500, kDetector, kDetector.centre_px());
    for (double t : angles) {
      const Eigen::Vector3d along(std::cos(t), std::sin(t), 0);
      views.push_back(ProjectionMatrix::compose(K, make_rigid(rotation_looking_along(along), Eigen::Vector3d(0, 0, 1000))));
    }
    b = ProjectionStack(n, kDetector.rows, kDetector.cols);
#pragma omp parallel for schedule(dynamic)
    for (int v = 0; v < n; ++v) {
      const Image im =
          render_line_integrals(phantom, views[static_cast<std::size_t>(v)], kDetector, {2, std::nullopt, std::nullopt});
      std::copy(im.pixels.begin(), im.pixels.end(), b.view(v));
    }
    if (counts > 0) {
      w = ProjectionStack(n, kDetector.rows, kDetector.cols);
      std::mt19937_64 rng(7);
      for (std::size_t i = 0; i < b.data.size(); ++i) {
        const double detected = std::max(1.0, double(std::poisson_distribution<int>(counts * std::exp(-b.data[i]))(rng)));
        b.data[i] = static_cast<float>(-std::log(detected / counts));
        w.data[i] = static_cast<float>(detected / counts);
      }
    }
    truth = Volume(layout);
    for (int k = 0; k < kSize; ++k)
      for (int j = 0; j < kSize; ++j)
        for (int i = 0; i < kSize; ++i) truth.at(i, j, k) = static_cast<float>(phantom.attenuation_at(layout.centre_of(i, j, k)));
  }
  double rmse(const Volume& x) const {
    double sum = 0;
    for (std::size_t i = 0; i < x.data.size(); ++i) sum += std::pow(double(x.data[i]) - truth.data[i], 2);
    return std::sqrt(sum / double(x.data.size()));
  }
};

const CircularScan& uneven_scan() {
  static const CircularScan scan(bunched_angles(90), 0);
  return scan;
}

std::vector<Eigen::Vector3d> source_directions(const std::vector<ProjectionMatrix>& views) {
  std::vector<Eigen::Vector3d> d;
  for (const auto& P : views) d.push_back(P.source_position());
  return d;
}

TEST(OrderedSubsets, PartitionTheViewsAndSpreadEachSubsetOverTheScan) {
  const auto& s = uneven_scan();
  const auto directions = source_directions(s.views);
  const int count = 10;
  const auto subsets = ordered_subsets(s.views, count);
  ASSERT_EQ(subsets.size(), 10u);
  std::vector<int> all;
  std::size_t smallest = 1000, largest = 0;
  for (const auto& subset : subsets) {
    all.insert(all.end(), subset.begin(), subset.end());
    smallest = std::min(smallest, subset.size());
    largest = std::max(largest, subset.size());
  }
  std::sort(all.begin(), all.end());
  for (int v = 0; v < 90; ++v) ASSERT_EQ(all[static_cast<std::size_t>(v)], v);
  EXPECT_LE(largest - smallest, 1u);
  // Contiguous blocks of views leave most of the scan's directions far from each subset; the
  // ordered subsets leave none. 9 evenly spread lines would come within 10 deg of every
  // direction; the views here are up to 7.2 deg apart, and the subsets compete for them: each
  // comes within 10 deg plus twice that spacing.
  for (int j = 0; j < count; ++j) {
    std::vector<int> block;
    for (int v = 9 * j; v < 9 * j + 9; ++v) block.push_back(v);
    const double ordered_gap = subset_coverage_gap_deg(directions, subsets[static_cast<std::size_t>(j)]);
    EXPECT_LE(ordered_gap, 10.0 + 2 * 7.2) << "subset " << j;
    EXPECT_GT(subset_coverage_gap_deg(directions, block), 2.5 * ordered_gap) << "block " << j;
  }
  // 36 views 10 deg apart on a full circle hold 18 lines, each seen from both sides. Subsets by
  // index (every 9th view) take two lines, each twice, 90 deg apart; ordered subsets
  // take four lines.
  std::vector<Eigen::Vector3d> circle;
  for (int k = 0; k < 36; ++k) circle.emplace_back(std::cos(k * M_PI / 18), std::sin(k * M_PI / 18), 0);
  EXPECT_NEAR(subset_coverage_gap_deg(circle, {0, 9, 18, 27}), 40.0, 1e-9);  // the 40 and 50 deg lines
  for (const auto& subset : ordered_subsets(circle, 9)) EXPECT_LE(subset_coverage_gap_deg(circle, subset), 30.0 + 1e-9);
  EXPECT_THROW(ordered_subsets(circle, 0), std::invalid_argument);
}

TEST(OsSqs, OneSubsetWithoutMomentumLowersTheCostEveryEpoch) {
  // Plain SQS is a majorise-minimise method: the cost cannot rise, with weights, a penalty and
  // non-negativity alike.
  const auto& s = uneven_scan();
  const JosephOperator A(s.views, s.layout, kDetector.rows, kDetector.cols);
  ProjectionStack w(s.b.views, s.b.rows, s.b.cols);
  for (std::size_t i = 0; i < w.data.size(); ++i) w.data[i] = static_cast<float>(std::exp(-s.b.data[i]));
  for (Regulariser r : {Regulariser::identity, Regulariser::gradient}) {
    OsSqsOptions o;
    o.epochs = 8;
    o.momentum = false;
    o.exact_cost = true;
    o.lambda = 2.0;
    o.regulariser = r;
    Volume x(s.layout);
    std::vector<int> every(90);
    for (int v = 0; v < 90; ++v) every[static_cast<std::size_t>(v)] = v;
    const SolverReport report = solve_os_sqs(A, s.b, &w, x, {every}, o);
    ASSERT_EQ(report.iterations.size(), 9u);
    for (std::size_t k = 1; k < report.iterations.size(); ++k)
      EXPECT_LT(report.iterations[k].cost, report.iterations[k - 1].cost) << to_string(r) << " epoch " << k;
    EXPECT_GE(*std::min_element(x.data.begin(), x.data.end()), 0.0f);
  }
}

TEST(OsSqs, ReachesThirtyCgIterationsQualityInAFifthOfThePasses) {
  // Each CG iteration and each OS-SQS epoch is one forward and one back projection of every view
  // (OS-SQS adds one of each for its curvature): 30 CG iterations against 5 epochs.
  const auto& s = uneven_scan();
  const JosephOperator A(s.views, s.layout, kDetector.rows, kDetector.cols);
  WlsOptions cg;
  cg.iterations = 30;
  cg.lambda = 1.0;
  cg.regulariser = Regulariser::gradient;
  Volume x_cg(s.layout);
  solve_wls_cg(A, s.b, nullptr, x_cg, cg);
  const double cg_rmse = s.rmse(x_cg);

  OsSqsOptions o;
  o.epochs = 5;
  o.lambda = cg.lambda;
  o.regulariser = cg.regulariser;
  Volume x(s.layout);
  solve_os_sqs(A, s.b, nullptr, x, ordered_subsets(s.views, 15), o);
  const double os_rmse = s.rmse(x);
  EXPECT_LE(os_rmse, cg_rmse) << "OS-SQS " << os_rmse << " against CG " << cg_rmse;

  // The same subsets as contiguous blocks of views (each an arc of the bunched scan) do worse.
  std::vector<std::vector<int>> blocks(15);
  for (int v = 0; v < 90; ++v) blocks[static_cast<std::size_t>(v / 6)].push_back(v);
  Volume x_blocks(s.layout);
  solve_os_sqs(A, s.b, nullptr, x_blocks, blocks, o);
  EXPECT_GT(s.rmse(x_blocks), 1.2 * os_rmse) << "blocks " << s.rmse(x_blocks) << " against ordered " << os_rmse;
}

// The steepest step along the x axis through the phantom's centre: how sharp the skull's edge is.
double steepest_step(const Volume& x) {
  const int j = kSize / 2, k = kSize / 2;
  double steepest = 0;
  for (int i = 0; i + 1 < kSize; ++i) steepest = std::max(steepest, std::abs(double(x.at(i + 1, j, k)) - x.at(i, j, k)));
  return steepest;
}

TEST(OsSqs, HuberBeatsTheBestQuadraticPenaltyOnFewNoisyViews) {
  // 40 views of a full circle at 2000 counts in the open beam. Each penalty's weight is the best
  // of a range four times apart; the Huber penalty's delta is a quarter of the phantom's smallest
  // contrast (0.1 of 0.02 / mm): its noise is smoothed as the quadratic smooths it, its edges not.
  std::vector<double> angles;
  for (int k = 0; k < 40; ++k) angles.push_back(2 * M_PI * k / 40);
  const CircularScan s(angles, 2000);
  const JosephOperator A(s.views, s.layout, kDetector.rows, kDetector.cols);
  const auto subsets = ordered_subsets(s.views, 5);
  struct Best {
    double rmse = 1e9, lambda = 0, step = 0;
  };
  const auto best_of = [&](double huber_delta) {
    Best best;
    for (double lambda : {2.0, 8.0, 32.0, 128.0, 512.0}) {
      OsSqsOptions o;
      o.epochs = 25;
      o.lambda = lambda;
      o.regulariser = Regulariser::gradient;
      o.huber_delta = huber_delta;
      Volume x(s.layout);
      solve_os_sqs(A, s.b, &s.w, x, subsets, o);
      if (s.rmse(x) < best.rmse) best = {s.rmse(x), lambda, steepest_step(x)};
    }
    return best;
  };
  const Best quadratic = best_of(0), huber = best_of(0.0005);
  EXPECT_LT(huber.rmse, 0.97 * quadratic.rmse) << "Huber (lambda " << huber.lambda << ") " << huber.rmse << ", quadratic (lambda "
                                               << quadratic.lambda << ") " << quadratic.rmse;
  EXPECT_GT(huber.step, 1.2 * quadratic.step) << "steepest step: Huber " << huber.step << ", quadratic " << quadratic.step;
  // The true step from skull (1.0) to brain (0.2) is 0.016 / mm: neither overshoots it much.
  EXPECT_LT(huber.step, 1.3 * 0.016);
}

TEST(HuberPenalty, GradientIsTheDerivativeOfTheValueAndTheCurvatureBoundsIt) {
  const VolumeLayout layout = VolumeLayout::centred({6, 5, 4}, Eigen::Vector3d::Ones());
  Volume x(layout);
  std::mt19937_64 rng(3);
  std::normal_distribution<double> noise(0, 0.01);
  for (float& v : x.data) v = static_cast<float>(noise(rng));
  const HuberPenalty p{2.0, 0.005};
  Volume g(layout), c(layout);
  add_huber_gradient_and_curvature(p, x, g, c);
  for (std::size_t i : {std::size_t{0}, std::size_t{17}, std::size_t{63}}) {
    Volume plus = x, minus = x;
    const double h = 1e-4;
    plus.data[i] += static_cast<float>(h);
    minus.data[i] -= static_cast<float>(h);
    const double numeric =
        (huber_penalty_value(p, plus) - huber_penalty_value(p, minus)) / (double(plus.data[i]) - minus.data[i]);
    EXPECT_NEAR(g.data[i], numeric, 1e-3 * std::abs(numeric) + 1e-6);
    // The separable surrogate lies above the penalty along this voxel's axis.
    for (double t : {-0.03, -0.004, 0.002, 0.05}) {
      Volume moved = x;
      moved.data[i] += static_cast<float>(t);
      const double surrogate = huber_penalty_value(p, x) + g.data[i] * t + 0.5 * c.data[i] * t * t;
      EXPECT_LE(huber_penalty_value(p, moved), surrogate + 1e-9);
    }
  }
  testing::expect_option_refused(
      HuberPenalty{1.0, 0.0}, [](auto&) {}, "HuberPenalty.delta");
}

TEST(OsSqs, RefusesSubsetsThatAreNotAPartition) {
  const auto& s = uneven_scan();
  const JosephOperator A(s.views, s.layout, kDetector.rows, kDetector.cols);
  Volume x(s.layout);
  std::vector<std::vector<int>> missing(1);
  for (int v = 0; v < 89; ++v) missing[0].push_back(v);
  EXPECT_THROW(solve_os_sqs(A, s.b, nullptr, x, missing, {}), std::invalid_argument);
  missing[0].push_back(0);
  EXPECT_THROW(solve_os_sqs(A, s.b, nullptr, x, missing, {}), std::invalid_argument);
}

}  // namespace
}  // namespace ctk

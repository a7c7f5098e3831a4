// Stopping by held-out views: the views moved out of the measurements exactly, the rule's
// bookkeeping, and on a noisy scan the iterate it returns against the truth.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <optional>
#include <random>
#include <string>
#include <vector>

#include "ctk/geom/trajectory.hpp"
#include "ctk/measure/measurements.hpp"
#include "ctk/phantoms/builtin_phantoms.hpp"
#include "ctk/phantoms/render.hpp"
#include "ctk/proj/joseph_operator.hpp"
#include "ctk/recon/held_out_fit.hpp"
#include "ctk/recon/ordered_subsets.hpp"
#include "ctk/recon/os_sqs.hpp"
#include "ctk/recon/reconstruction_run.hpp"
#include "ctk/recon/wls_cg.hpp"

namespace ctk {
namespace {

constexpr int kSize = 32;
const Detector kDetector{48, 48, 1.6, 1.6};

// 128 views on a circle of a Shepp-Logan filling the volume, Poisson noise at 1000 counts in the
// open beam: noisy enough that an unregularised solve passes its best image early.
struct NoisyScan {
  VolumeLayout layout = VolumeLayout::centred({kSize, kSize, kSize}, Eigen::Vector3d::Constant(1.0));
  Phantom phantom = shepp_logan_phantom(13.0, 0.04);
  std::vector<ProjectionMatrix> views;
  ProjectionStack b, w;
  Volume truth;

  NoisyScan() {
    const int n = 128;
    const Intrinsics K = Intrinsics::from_setup(1500, kDetector, kDetector.centre_px());
    for (int k = 0; k < n; ++k) {
      const double t = 2 * M_PI * k / n;
      views.push_back(ProjectionMatrix::compose(
          K, make_rigid(rotation_looking_along({std::cos(t), std::sin(t), 0}), Eigen::Vector3d(0, 0, 1000))));
    }
    b = ProjectionStack(n, kDetector.rows, kDetector.cols);
    w = ProjectionStack(n, kDetector.rows, kDetector.cols);
    std::mt19937_64 rng(11);
    for (int v = 0; v < n; ++v) {
      const Image im =
          render_line_integrals(phantom, views[static_cast<std::size_t>(v)], kDetector, {2, std::nullopt, std::nullopt});
      std::copy(im.pixels.begin(), im.pixels.end(), b.view(v));
    }
    for (std::size_t i = 0; i < b.data.size(); ++i) {
      const double detected = std::max(1.0, double(std::poisson_distribution<int>(1000 * std::exp(-b.data[i]))(rng)));
      b.data[i] = static_cast<float>(-std::log(detected / 1000));
      w.data[i] = static_cast<float>(detected / 1000);
    }
    truth = voxelised(phantom, layout);
  }
  double rmse(const Volume& x) const {
    double sum = 0;
    for (std::size_t i = 0; i < x.data.size(); ++i) sum += std::pow(double(x.data[i]) - truth.data[i], 2);
    return std::sqrt(sum / double(x.data.size()));
  }
};

const NoisyScan& noisy_scan() {
  static const NoisyScan scan;
  return scan;
}

Measurements as_measurements(const NoisyScan& s) {
  Measurements m;
  for (int v = 0; v < s.b.views; ++v) m.view_indices.push_back(100 + v);
  m.matrices = s.views;
  m.line_integrals = s.b;
  m.weights = s.w;
  return m;
}

TEST(TakeViews, MovesTheChosenViewsOutAndKeepsTheRestInOrder) {
  const NoisyScan& s = noisy_scan();
  Measurements m = as_measurements(s);
  const std::vector<int> chosen{0, 5, 127};
  const Measurements held = take_views(m, chosen);
  ASSERT_EQ(held.view_indices, (std::vector<int>{100, 105, 227}));
  ASSERT_EQ(m.view_indices.size(), 125u);
  EXPECT_EQ(m.view_indices[0], 101);
  EXPECT_EQ(m.view_indices[4], 106);
  EXPECT_EQ(m.view_indices.back(), 226);
  ASSERT_EQ(m.line_integrals.views, 125);
  ASSERT_EQ(m.weights.views, 125);
  const std::size_t n = m.line_integrals.pixels_per_view();
  for (std::size_t k = 0; k < chosen.size(); ++k) {
    EXPECT_TRUE(std::equal(held.line_integrals.view(static_cast<int>(k)), held.line_integrals.view(static_cast<int>(k)) + n,
                           s.b.view(chosen[k])));
    EXPECT_TRUE(
        std::equal(held.weights.view(static_cast<int>(k)), held.weights.view(static_cast<int>(k)) + n, s.w.view(chosen[k])));
    EXPECT_TRUE(held.matrices[k].matrix().isApprox(s.views[static_cast<std::size_t>(chosen[k])].matrix()));
  }
  // What stays is compacted: stack view 4 is scan view 6 (1..4 and 6 kept, 5 taken).
  EXPECT_TRUE(std::equal(m.line_integrals.view(4), m.line_integrals.view(4) + n, s.b.view(6)));
  EXPECT_TRUE(m.matrices[4].matrix().isApprox(s.views[6].matrix()));
  EXPECT_THROW(take_views(m, {3, 2}), std::invalid_argument);
  EXPECT_THROW(take_views(m, {125}), std::invalid_argument);
}

TEST(HeldOutViews, AreOneOrderedSubsetSpreadOverTheCircle) {
  const NoisyScan& s = noisy_scan();
  const std::vector<int> held = held_out_positions(s.views, 32);
  ASSERT_EQ(held.size(), 4u);  // 128 / 32
  EXPECT_TRUE(std::is_sorted(held.begin(), held.end()));
  // Four views of a full circle, as lines (a view and its opposite see the same line integrals),
  // 45 deg apart give or take the views' spacing of 2.8125 deg.
  std::vector<double> lines;
  lines.reserve(held.size());
  for (int v : held) lines.push_back(std::fmod(v * 2.8125, 180.0));
  std::sort(lines.begin(), lines.end());
  for (std::size_t k = 0; k < lines.size(); ++k) {
    const double gap = k + 1 < lines.size() ? lines[k + 1] - lines[k] : lines.front() + 180 - lines[k];
    EXPECT_NEAR(gap, 45.0, 2.8125 + 1e-9) << "the lines at " << lines[k] << " deg and the next";
  }
  EXPECT_TRUE(held_out_positions(s.views, 129).empty());
  EXPECT_TRUE(held_out_positions(s.views, 0).empty());
}

// Two held-out views of the noisy scan's truth, projected exactly, and the truth scaled by `f`.
struct ExactHeldOut {
  const NoisyScan& s = noisy_scan();
  std::shared_ptr<JosephOperator> A;
  ProjectionStack exact;
  ExactHeldOut()
      : A(std::make_shared<JosephOperator>(std::vector<ProjectionMatrix>{s.views[0], s.views[40]}, s.layout, kDetector.rows,
                                           kDetector.cols)),
        exact(2, kDetector.rows, kDetector.cols) {
    A->apply(s.truth, exact);
  }
  Volume truth_times(float f) const {
    Volume v = s.truth;
    for (float& x : v.data) x *= f;
    return v;
  }
};

TEST(HeldOutFit, EndsTheRunAtTheFirstIterationThatDidNotImproveAndReturnsTheLastThatDid) {
  const ExactHeldOut h;
  const NoisyScan& s = h.s;
  HeldOutFit judge(h.A, h.exact, ProjectionStack());
  const StoppingRule rule = judge.rule();
  const Volume half = h.truth_times(0.5f), twice = h.truth_times(2.0f);
  judge.observe(0, Volume(s.layout));
  EXPECT_FALSE(rule());
  judge.observe(1, half);
  EXPECT_FALSE(rule());
  judge.observe(2, s.truth);  // fits exactly: the best
  EXPECT_FALSE(rule());
  judge.observe(3, twice);
  const auto reason = rule();
  ASSERT_TRUE(reason);
  EXPECT_NE(reason->find("2 held-out views stopped improving beyond their noise after iteration 2"), std::string::npos)
      << *reason;
  Volume x = twice;
  EXPECT_EQ(judge.restore_best(x), 2);
  EXPECT_EQ(x.data, s.truth.data);
  const nlohmann::json r = judge.report();
  EXPECT_EQ(r["best_iteration"], 2);
  EXPECT_EQ(r["fit"].size(), 4u);
  EXPECT_DOUBLE_EQ(r["fit"][2].get<double>(), 0.0);
  // 1/2 ||A (x/2 - x)||^2 = 1/8 ||A x||^2, and 1/2 ||A (2x - x)||^2 = 1/2 ||A x||^2.
  EXPECT_NEAR(r["fit"][3].get<double>(), 4 * r["fit"][1].get<double>(), 1e-6 * r["fit"][3].get<double>());
}

// A judge returning `result`, shown the start, the `improving` iterates (each closer to the
// truth) and then one that is worse: why it stopped, the last improving iteration, the volume it
// returns and what the report says it is.
struct Judged {
  std::optional<std::string> reason;
  int last_improving = -1;
  Volume x;
  nlohmann::json result_iterations;
};

Judged judged(const ExactHeldOut& h, HeldOutResult result, const std::vector<Volume>& improving) {
  HeldOutFit judge(h.A, h.exact, ProjectionStack());
  judge.return_result(result);
  judge.observe(0, Volume(h.s.layout));
  int iteration = 1;
  for (const Volume& v : improving) judge.observe(iteration++, v);
  Judged out;
  out.x = h.truth_times(2.0f);
  judge.observe(iteration, out.x);
  out.reason = judge.rule()();
  out.last_improving = judge.restore_best(out.x);
  out.result_iterations = judge.report()["result_iterations"];
  return out;
}

TEST(HeldOutFit, ReturnsTheMeanOfTheLastTwoImprovingIteratesPastTheFirstWhenAsked) {
  const ExactHeldOut h;
  const NoisyScan& s = h.s;
  // Improving at 1, 2 and 3, not at 4: the mean of 2 and 3.
  const Judged three = judged(h, HeldOutResult::mean_of_last_two, {h.truth_times(0.25f), h.truth_times(0.5f), s.truth});
  ASSERT_TRUE(three.reason);
  EXPECT_NE(three.reason->find("after iteration 3 (the mean of its iterate and the one before is the result)"), std::string::npos)
      << *three.reason;
  EXPECT_EQ(three.last_improving, 3);
  for (std::size_t i = 0; i < three.x.data.size(); ++i) ASSERT_FLOAT_EQ(three.x.data[i], 0.75f * s.truth.data[i]) << i;
  EXPECT_EQ(three.result_iterations, nlohmann::json({2, 3}));
  // Improving at 1 and 2: the first is too far from the data to average, so iterate 2 alone.
  const Judged two = judged(h, HeldOutResult::mean_of_last_two, {h.truth_times(0.5f), s.truth});
  ASSERT_TRUE(two.reason);
  EXPECT_EQ(two.last_improving, 2);
  EXPECT_EQ(two.x.data, s.truth.data);
  EXPECT_EQ(two.result_iterations, nlohmann::json({2}));
}

TEST(HeldOutFit, ReturnsTheImprovingIterateBeforeTheLastWhenItIsPastTheFirst) {
  const ExactHeldOut h;
  const NoisyScan& s = h.s;
  // Improving at 1, 2 and 3, not at 4: iterate 2.
  const Volume half = h.truth_times(0.5f);
  const Judged three = judged(h, HeldOutResult::one_before, {h.truth_times(0.25f), half, s.truth});
  ASSERT_TRUE(three.reason);
  EXPECT_NE(three.reason->find("after iteration 3 (the iterate of 2, the improving one before it, is the result)"),
            std::string::npos)
      << *three.reason;
  EXPECT_EQ(three.last_improving, 3);
  EXPECT_EQ(three.x.data, half.data);
  EXPECT_EQ(three.result_iterations, nlohmann::json({2}));
  // Improving at 1 and 2: the first is no result, so iterate 2.
  const Judged two = judged(h, HeldOutResult::one_before, {half, s.truth});
  ASSERT_TRUE(two.reason);
  EXPECT_EQ(two.last_improving, 2);
  EXPECT_EQ(two.x.data, s.truth.data);
  EXPECT_EQ(two.result_iterations, nlohmann::json({2}));
}

// On the noisy scan, each solver on the views not held out, with the rule and without it (to
// the same epoch or iteration count), against the truth.
struct Stopped {
  double result_rmse = 0, best_rmse = 0, fixed_rmse = 0;
  int iterations_run = 0, limit = 0;
};

Stopped run_with_and_without_the_rule(bool os_sqs) {
  const NoisyScan& s = noisy_scan();
  Measurements m = as_measurements(s);
  const Measurements held = take_views(m, held_out_positions(s.views, 32));
  const JosephOperator A(m.matrices, s.layout, kDetector.rows, kDetector.cols);
  const auto A_held = std::make_shared<JosephOperator>(held.matrices, s.layout, kDetector.rows, kDetector.cols);
  const int limit = os_sqs ? 8 : 30;
  Stopped out;
  out.limit = limit;
  std::vector<double> rmse;
  for (const bool ruled : {false, true}) {
    HeldOutFit judge(A_held, held.line_integrals, held.weights);
    judge.return_result(held_out_result(os_sqs ? ReconstructionMethod::os_sqs : ReconstructionMethod::wls_cg));
    Volume x(s.layout);
    const IterationCallback follow = [&](const IterationLog& log) {
      judge.observe(log.iteration, x);
      if (!ruled) rmse.push_back(s.rmse(x));
    };
    SolverReport report;
    if (os_sqs) {
      OsSqsOptions o;
      o.epochs = limit;
      report =
          solve_os_sqs(A, m.line_integrals, &m.weights, x, ordered_subsets(m.matrices, default_subset_count(A.range().views)), o,
                       follow, {}, ruled ? judge.rule() : StoppingRule());
    } else {
      WlsOptions o;
      o.iterations = limit;
      report = solve_wls_cg(A, m.line_integrals, &m.weights, x, o, follow, nullptr, ruled ? judge.rule() : StoppingRule());
    }
    if (ruled) {
      judge.restore_best(x);
      out.result_rmse = s.rmse(x);
      out.iterations_run = report.iterations.back().iteration;
      EXPECT_NE(report.stop_reason.find("held-out views stopped improving"), std::string::npos) << report.stop_reason;
    }
  }
  out.best_rmse = *std::min_element(rmse.begin(), rmse.end());
  out.fixed_rmse = rmse.back();
  return out;
}

TEST(HeldOutFit, StopsEachSolverNearItsBestIterate) {
  // Measured: at the limit OS-SQS ends 1.70 and WLS-CG 3.35 times its best RMSE; the rule returned
  // each one's best iterate (epoch 2, iteration 4).
  for (const bool os_sqs : {true, false}) {
    const Stopped r = run_with_and_without_the_rule(os_sqs);
    std::cout << (os_sqs ? "OS-SQS" : "WLS-CG") << ": stopped after " << r.iterations_run << " of " << r.limit << ", RMSE "
              << r.result_rmse << ", its best " << r.best_rmse << ", at the limit " << r.fixed_rmse << "\n";
    EXPECT_LT(r.iterations_run, r.limit);
    EXPECT_LE(r.result_rmse, 1.05 * r.best_rmse);
    EXPECT_LT(r.result_rmse, (os_sqs ? 0.95 : 0.6) * r.fixed_rmse);
  }
}

}  // namespace
}  // namespace ctk

// The operator interface and its variants: each pair (A, A') adjoint to float rounding, alone and
// composed; a subset of views equal to those views of the whole; the Joseph operator the
// projector itself; shapes refused with a message.
#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <random>
#include <stdexcept>
#include <vector>

#include "ctk/geom/trajectory.hpp"
#include "ctk/proj/arc_averaged_projection.hpp"
#include "ctk/proj/binned_projection.hpp"
#include "ctk/proj/joseph_operator.hpp"
#include "ctk/proj/weighted_projection.hpp"

namespace ctk {
namespace {

const Detector kDetector{30, 22, 1.0, 1.0};
const VolumeLayout kLayout = VolumeLayout::centred({20, 18, 16}, {1.0, 1.2, 0.9});

std::vector<ProjectionMatrix> random_views(int count, std::uint64_t seed) {
  std::vector<ProjectionMatrix> views;
  const Intrinsics K = Intrinsics::from_setup(500, kDetector, kDetector.centre_px());
  for (const auto& dir : random_directions(count, seed))
    views.push_back(ProjectionMatrix::compose(K, make_rigid(rotation_looking_along(dir), Eigen::Vector3d(0, 0, 250))));
  return views;
}

void fill_random(FloatBuffer& v, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  for (float& x : v) x = u(rng);
}

double dot(const FloatBuffer& a, const FloatBuffer& b) {
  double s = 0;
  for (std::size_t i = 0; i < a.size(); ++i) s += static_cast<double>(a[i]) * b[i];
  return s;
}

// |<A x, y> - <x, A' y>| / (|A x| |y|) for random x and y.
double adjoint_mismatch(const ProjectionOperator& A, std::uint64_t seed) {
  Volume x = A.domain_zeros(), Aty;
  ProjectionStack y = A.range_zeros(), Ax;
  fill_random(x.data, seed);
  fill_random(y.data, seed + 1);
  A.apply(x, Ax);
  A.apply_adjoint(y, Aty);
  return std::abs(dot(Ax.data, y.data) - dot(x.data, Aty.data)) / std::sqrt(dot(Ax.data, Ax.data) * dot(y.data, y.data));
}

std::shared_ptr<const JosephOperator> joseph(int views, std::uint64_t seed) {
  return std::make_shared<JosephOperator>(random_views(views, seed), kLayout, kDetector.rows, kDetector.cols);
}

ProjectionStack random_factors(const StackShape& s, std::uint64_t seed) {
  ProjectionStack f(s.views, s.rows, s.cols);
  fill_random(f.data, seed);
  return f;
}

// Sub-views spread over a small turn about the volume's z axis.
std::vector<std::vector<ProjectionMatrix>> arcs(const std::vector<ProjectionMatrix>& views, int samples, double arc_rad) {
  std::vector<std::vector<ProjectionMatrix>> out;
  for (const auto& P : views) {
    out.emplace_back();
    for (int s = 0; s < samples; ++s) {
      const double a = arc_rad * ((s + 0.5) / samples - 0.5);
      Rigid turn = Rigid::Identity();
      turn.linear() = Eigen::AngleAxisd(a, Eigen::Vector3d::UnitZ()).toRotationMatrix();
      out.back().push_back(ProjectionMatrix(Matrix34d(P.matrix() * turn.matrix())));
    }
  }
  return out;
}

TEST(ProjectionOperators, EveryVariantAndACompositionIsAdjointToFloatRounding) {
  const auto A = joseph(7, 3);
  const auto binned = std::make_shared<BinnedProjection>(A, 3);
  const auto weighted = std::make_shared<WeightedProjection>(A, random_factors(A->range(), 11));
  const auto arc = std::make_shared<ArcAveragedProjection>(arcs(A->views(), 4, 0.05), kLayout, kDetector.rows, kDetector.cols);
  const auto composed = std::make_shared<WeightedProjection>(binned, random_factors(binned->range(), 12));
  EXPECT_EQ(binned->range(), (StackShape{7, 7, 10}));  // a last partial row (22 = 3 * 7 + 1) is dropped
  for (const ProjectionOperator* op :
       std::vector<const ProjectionOperator*>{A.get(), binned.get(), weighted.get(), arc.get(), composed.get()})
    EXPECT_LT(adjoint_mismatch(*op, 21), 1e-5);
}

TEST(ProjectionOperators, TheJosephOperatorIsTheProjectorOnItsViews) {
  const auto A = joseph(5, 4);
  Volume x(kLayout);
  fill_random(x.data, 5);
  ProjectionStack by_operator, by_projector(5, kDetector.rows, kDetector.cols);
  A->apply(x, by_operator);
  JosephProjector().forward(x, A->views(), by_projector);
  EXPECT_EQ(by_operator.data, by_projector.data);
}

TEST(ProjectionOperators, ASubsetProjectsItsViewsAsTheWholeDoes) {
  const auto A = joseph(6, 7);
  const auto composed = std::make_shared<WeightedProjection>(std::make_shared<BinnedProjection>(A, 2),
                                                             random_factors(BinnedProjection(A, 2).range(), 8));
  const auto arc = std::make_shared<ArcAveragedProjection>(arcs(A->views(), 3, 0.04), kLayout, kDetector.rows, kDetector.cols);
  Volume x(kLayout);
  fill_random(x.data, 9);
  const std::vector<int> chosen{4, 1, 5};
  for (const ProjectionOperator* op : std::vector<const ProjectionOperator*>{A.get(), composed.get(), arc.get()}) {
    ProjectionStack whole, part;
    op->apply(x, whole);
    const auto sub = op->subset(chosen);
    ASSERT_EQ(sub->range().views, 3);
    sub->apply(x, part);
    for (std::size_t i = 0; i < chosen.size(); ++i) {
      const float* w = whole.view(chosen[i]);
      const float* p = part.view(static_cast<int>(i));
      double diff = 0, norm = 0;
      for (std::size_t k = 0; k < whole.pixels_per_view(); ++k) {
        diff += std::pow(double(w[k]) - p[k], 2);
        norm += double(w[k]) * w[k];
      }
      EXPECT_LE(std::sqrt(diff / norm), 1e-6) << "view " << chosen[i];
    }
  }
}

TEST(ProjectionOperators, AnArcOfOneRepeatedViewIsThatView) {
  const auto A = joseph(3, 10);
  std::vector<std::vector<ProjectionMatrix>> repeated;
  for (const auto& P : A->views()) repeated.push_back({P, P, P, P});
  const ArcAveragedProjection arc(repeated, kLayout, kDetector.rows, kDetector.cols);
  Volume x(kLayout);
  fill_random(x.data, 13);
  ProjectionStack a, b;
  A->apply(x, a);
  arc.apply(x, b);
  for (std::size_t i = 0; i < a.data.size(); ++i) EXPECT_NEAR(a.data[i], b.data[i], 1e-5f * (1 + std::abs(a.data[i])));
}

TEST(ProjectionOperators, ShapesThatDoNotFitAreRefused) {
  const auto A = joseph(4, 14);
  Volume wrong(VolumeLayout::centred({20, 18, 15}, {1.0, 1.2, 0.9}));
  ProjectionStack y;
  EXPECT_THROW(A->apply(wrong, y), std::invalid_argument);
  Volume x;
  EXPECT_THROW(A->apply_adjoint(ProjectionStack(4, kDetector.rows, kDetector.cols + 1), x), std::invalid_argument);
  EXPECT_THROW(A->subset({0, 4}), std::out_of_range);
  EXPECT_THROW(A->subset({-1}), std::out_of_range);
  EXPECT_THROW(WeightedProjection(A, ProjectionStack(3, kDetector.rows, kDetector.cols)), std::invalid_argument);
  EXPECT_THROW(BinnedProjection(A, 23), std::invalid_argument);
  EXPECT_THROW(ArcAveragedProjection({{}}, kLayout, kDetector.rows, kDetector.cols), std::invalid_argument);
  // A mismatched output is reshaped, not refused.
  ProjectionStack reshaped(1, 1, 1);
  A->apply(A->domain_zeros(), reshaped);
  EXPECT_EQ(StackShape::of(reshaped), A->range());
}

}  // namespace
}  // namespace ctk

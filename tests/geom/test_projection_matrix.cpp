#include "ctk/geom/projection_matrix.hpp"

#include <gtest/gtest.h>

#include <random>

#include "ctk/geom/astra.hpp"

namespace ctk {
namespace {

struct RandomView {
  Intrinsics K;
  Rigid T;
};

// Random intrinsics with skew and unequal focal lengths, random pose with the origin in front.
RandomView random_view(std::mt19937_64& rng) {
  std::uniform_real_distribution<double> u(-1, 1);
  RandomView v;
  v.K = {2000 + 1500 * u(rng), 2000 + 1500 * u(rng), 5 * u(rng), 300 + 100 * u(rng), 250 + 100 * u(rng)};
  const Eigen::Vector3d axis(u(rng), u(rng), u(rng));
  v.T = make_rigid(rotation_about(axis, M_PI * u(rng)), Eigen::Vector3d(30 * u(rng), 30 * u(rng), 1200 + 300 * u(rng)));
  return v;
}

TEST(ProjectionMatrix, ComposeDecomposeRoundTrip) {
  std::mt19937_64 rng(1);
  for (int i = 0; i < 30; ++i) {
    const RandomView v = random_view(rng);
    const auto P = ProjectionMatrix::compose(v.K, v.T);
    const auto d = P.decompose();
    EXPECT_NEAR(d.intrinsics.fu_px, v.K.fu_px, 1e-10 * v.K.fu_px);
    EXPECT_NEAR(d.intrinsics.fv_px, v.K.fv_px, 1e-10 * v.K.fv_px);
    EXPECT_NEAR(d.intrinsics.skew_px, v.K.skew_px, 1e-9);
    EXPECT_NEAR(d.intrinsics.u0_px, v.K.u0_px, 1e-9);
    EXPECT_NEAR(d.intrinsics.v0_px, v.K.v0_px, 1e-9);
    EXPECT_LT((d.T_camera_frame.linear() - v.T.linear()).cwiseAbs().maxCoeff(), 1e-10);
    EXPECT_LT((d.T_camera_frame.translation() - v.T.translation()).cwiseAbs().maxCoeff(), 1e-8);
    EXPECT_LT(max_abs_difference(ProjectionMatrix::compose(d.intrinsics, d.T_camera_frame), P), 1e-10 * P.matrix().norm());
  }
}

TEST(ProjectionMatrix, NormalisedSoDepthIsInMillimetres) {
  std::mt19937_64 rng(2);
  const RandomView v = random_view(rng);
  const auto P = ProjectionMatrix(3.7 * ProjectionMatrix::compose(v.K, v.T).matrix());
  EXPECT_NEAR((P.matrix().block<1, 3>(2, 0).norm()), 1.0, 1e-14);
  const Eigen::Vector3d X(3, -2, 7);
  EXPECT_NEAR(P.depth(X), (v.T * X).z(), 1e-9);
}

TEST(ProjectionMatrix, SourcePrincipalRayAndProjection) {
  std::mt19937_64 rng(3);
  for (int i = 0; i < 10; ++i) {
    const RandomView v = random_view(rng);
    const auto P = ProjectionMatrix::compose(v.K, v.T);
    const Eigen::Vector3d C = P.source_position();
    EXPECT_LT((C - v.T.inverse().translation()).norm(), 1e-9);
    // The principal ray hits the principal point.
    const Eigen::Vector2d pp = P.project(C + 500 * P.principal_ray());
    EXPECT_NEAR(pp.x(), v.K.u0_px, 1e-8);
    EXPECT_NEAR(pp.y(), v.K.v0_px, 1e-8);
    // A point on the ray through a pixel projects back to that pixel.
    const Eigen::Vector2d uv(123.25, 456.5);
    const Eigen::Vector2d back = P.project(C + 900 * P.ray_direction(uv));
    EXPECT_LT((back - uv).norm(), 1e-8);
    EXPECT_GT(P.depth(C + 900 * P.ray_direction(uv)), 0);
  }
}

TEST(ProjectionMatrix, JacobianMatchesFiniteDifferences) {
  std::mt19937_64 rng(4);
  const RandomView v = random_view(rng);
  const auto P = ProjectionMatrix::compose(v.K, v.T);
  const Eigen::Vector3d X(10, -20, 5);
  Eigen::Matrix<double, 2, 3> J;
  P.project(X, &J);
  for (int k = 0; k < 3; ++k) {
    Eigen::Vector3d h = Eigen::Vector3d::Zero();
    h[k] = 1e-4;
    const Eigen::Vector2d fd = (P.project(X + h) - P.project(X - h)) / 2e-4;
    EXPECT_LT((fd - J.col(k)).norm(), 1e-6);
  }
  double uv[2];
  const auto p = P.row_major();
  project_point(p.data(), X.data(), uv);
  EXPECT_NEAR(uv[0], P.project(X).x(), 1e-12);
}

TEST(ProjectionMatrix, MirroredDetectorDecomposesWithNegativeFu) {
  Intrinsics K{-2000, 2100, 0, 300, 200};
  const Rigid T = make_rigid(rotation_about(Eigen::Vector3d(1, 2, 3), 0.4), Eigen::Vector3d(1, 2, 1000));
  const auto P = ProjectionMatrix::compose(K, T);
  const auto d = P.decompose();
  EXPECT_NEAR(d.intrinsics.fu_px, -2000, 1e-7);
  EXPECT_NEAR(d.T_camera_frame.linear().determinant(), 1.0, 1e-12);
  EXPECT_LT(max_abs_difference(ProjectionMatrix::compose(d.intrinsics, d.T_camera_frame), P), 1e-10);
}

TEST(ProjectionMatrix, SingularMatrixIsRejected) { EXPECT_THROW(ProjectionMatrix(Matrix34d::Zero()), std::invalid_argument); }

TEST(TiltedDetector, MatchesRayPlaneIntersection) {
  const Detector det{720, 720, 0.6, 0.6};
  const double f = 2150;
  const Intrinsics K = Intrinsics::from_setup(f, det, {359.5, 359.5});
  EXPECT_LT((tilted_detector_matrix(K, f, det, 0, 0) - K.K()).cwiseAbs().maxCoeff(), 1e-12);
  const double a = 0.02, b = -0.03;
  const Eigen::Matrix3d M = tilted_detector_matrix(K, f, det, a, b);
  const Eigen::Matrix3d Rt =
      (Eigen::AngleAxisd(a, Eigen::Vector3d::UnitX()) * Eigen::AngleAxisd(b, Eigen::Vector3d::UnitY())).toRotationMatrix();
  const Eigen::Vector3d c0(0, 0, f);
  for (const Eigen::Vector3d& X : {Eigen::Vector3d(10, 20, 1360), Eigen::Vector3d(-40, 5, 1300), Eigen::Vector3d(0, 0, 1)}) {
    const Eigen::Vector3d n = Rt.col(2);
    const Eigen::Vector3d hit = X * (n.dot(c0) / n.dot(X)) - c0;
    const Eigen::Vector2d expected(K.u0_px + Rt.col(0).dot(hit) / 0.6, K.v0_px + Rt.col(1).dot(hit) / 0.6);
    const Eigen::Vector3d p = M * X;
    EXPECT_LT((Eigen::Vector2d(p.x() / p.z(), p.y() / p.z()) - expected).norm(), 1e-9);
  }
  // Any tilted P still decomposes into an equivalent upper-triangular K and rotation.
  const auto P = ProjectionMatrix::compose(M, make_rigid(Eigen::Matrix3d::Identity(), Eigen::Vector3d(0, 0, 1360)));
  const auto d = P.decompose();
  EXPECT_LT(max_abs_difference(ProjectionMatrix::compose(d.intrinsics, d.T_camera_frame), P), 1e-10);
}

TEST(Astra, ConeVecRoundTripProjectsIdentically) {
  std::mt19937_64 rng(5);
  const Detector det{720, 600, 0.6, 0.55};
  std::uniform_real_distribution<double> u(-60, 60);
  for (int i = 0; i < 30; ++i) {
    const RandomView v = random_view(rng);
    const auto P = ProjectionMatrix::compose(v.K, v.T);
    const ConeVec vec = to_cone_vec(P, det);
    const auto P2 = from_cone_vec(vec, det);
    for (int k = 0; k < 20; ++k) {
      const Eigen::Vector3d X(u(rng), u(rng), u(rng));
      EXPECT_LT((P.project(X) - P2.project(X)).norm(), 1e-9);
    }
    // For a composed matrix the exported detector is the physical one: one column step = pitch.
    EXPECT_NEAR(Eigen::Vector3d(vec[6], vec[7], vec[8]).norm(), 0.6, 1e-9);
  }
}

TEST(Astra, PixelCentresLieWhereTheVectorsSay) {
  // ASTRA semantics: pixel (r, c) centre = d + (c - (cols-1)/2) u + (r - (rows-1)/2) v.
  const Detector det{768, 972, 0.1496, 0.1496};
  const ConeVec vec{-0.0005, -66.0014, 14.9202, -0.0005, 133.0048, -29.9998, 0.14959, 0, -0.00131, 0.00131, 0, 0.14959};
  const auto P = from_cone_vec(vec, det);
  const Eigen::Vector3d s(vec[0], vec[1], vec[2]), d(vec[3], vec[4], vec[5]), uu(vec[6], vec[7], vec[8]),
      vv(vec[9], vec[10], vec[11]);
  for (const Eigen::Vector2d& cr : {Eigen::Vector2d(0, 0), Eigen::Vector2d(383.5, 485.5), Eigen::Vector2d(700, 12)}) {
    const Eigen::Vector3d X = d + (cr.x() - 383.5) * uu + (cr.y() - 485.5) * vv;
    EXPECT_LT((P.project(X) - cr).norm(), 1e-9);
    EXPECT_LT((P.project(s + 0.37 * (X - s)) - cr).norm(), 1e-9);
  }
  EXPECT_LT((P.source_position() - s).norm(), 1e-9);
}

}  // namespace
}  // namespace ctk

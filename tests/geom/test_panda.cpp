#include "ctk/geom/panda.hpp"

#include <gtest/gtest.h>

namespace ctk::panda {
namespace {

void expect_pose(const Joints& q, const Eigen::Vector3d& p_mm, const Eigen::Quaterniond& expected) {
  const Rigid T = forward_kinematics(q);
  EXPECT_LT((T.translation() - p_mm).cwiseAbs().maxCoeff(), 1e-3) << T.translation().transpose();
  Eigen::Quaterniond got(T.linear());
  // Up to sign: q and -q are the same rotation.
  const double sign = got.coeffs().dot(expected.coeffs()) < 0 ? -1.0 : 1.0;
  EXPECT_LT((sign * got.coeffs() - expected.coeffs()).cwiseAbs().maxCoeff(), 1e-5)
      << got.coeffs().transpose() << " vs " << expected.coeffs().transpose();
}

// Peer vectors from the frankx project's kinematics test (flange frame, mm).
TEST(PandaForwardKinematics, MatchesPublishedPeerVectors) {
  expect_pose({0.4401378, -1.720145, -0.4573823, -2.394063, -0.6454046, 0.5917417, 0.4929689}, {12.91572, -219.187, 556.6107},
              Eigen::Quaterniond(0.01460959, 0.9677397, -0.2340099, -0.09222686));
  expect_pose({0.3027361, -1.755932, -0.3099454, -2.759472, -0.1217491, 2.112061, 1.139796}, {117.0532, -67.54467, 647.0401},
              Eigen::Quaterniond(-0.406576, 0.7517108, -0.3960603, 0.3358022));
}

TEST(PandaForwardKinematics, ZeroAndReadyPoses) {
  EXPECT_LT((forward_kinematics({0, 0, 0, 0, 0, 0, 0}).translation() - Eigen::Vector3d(88, 0, 926)).norm(), 1e-9);
  const Rigid ready = forward_kinematics({0, -M_PI / 4, 0, -3 * M_PI / 4, 0, M_PI / 2, M_PI / 4});
  EXPECT_LT((ready.translation() - Eigen::Vector3d(306.891, 0, 590.282)).cwiseAbs().maxCoeff(), 1e-3);
  // In the ready pose the flange points straight down.
  EXPECT_LT((ready.linear().col(2) - Eigen::Vector3d(0, 0, -1)).norm(), 1e-12);
}

TEST(PandaForwardKinematics, TemplateAgreesWithDouble) {
  const Joints q{0.1, -0.5, 0.3, -2.0, 0.2, 1.5, -0.4};
  const Eigen::Matrix4d M = forward_kinematics_matrix<double>(q.data());
  EXPECT_LT((M - forward_kinematics(q).matrix()).cwiseAbs().maxCoeff(), 1e-12);
}

TEST(PandaJointLimits, OutOfLimitJointsAreFlagged) {
  EXPECT_TRUE(joints_out_of_limits({0, -M_PI / 4, 0, -3 * M_PI / 4, 0, M_PI / 2, M_PI / 4}).empty());
  const Joints bad{3.0, 0, 0, 0.0, 0, 1, std::nan("")};  // q1 too large, q4 above -0.0698, q7 NaN
  EXPECT_EQ(joints_out_of_limits(bad), (std::vector<int>{0, 3, 6}));
  EXPECT_NE(describe_limit_violations(bad).find("q4"), std::string::npos);
}

}  // namespace
}  // namespace ctk::panda

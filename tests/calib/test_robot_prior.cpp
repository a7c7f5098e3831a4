// Each view's pose from its spheres and the robot's prior together (libcalib/robot_prior.hpp), on
// simulated scans of the reference setup whose robot base is not where the scan file says: poses
// against the truth, the repeatability the scan measures, and a robot worse than its model.
#include <gtest/gtest.h>

#include "../test_support.hpp"
#include "ctk/calib/robot_prior.hpp"
#include "ctk/geom/trajectory.hpp"
#include "ctk/phantoms/scan_simulation.hpp"
#include "pose_errors.hpp"

namespace ctk {
namespace {

ScanSimulation reference_scan(std::vector<PlannedView> trajectory, const PandaSetup& setup) {
  ScanSimulation sim;
  sim.setup = setup;
  sim.holder = reference_helix_holder();
  sim.trajectory = std::move(trajectory);
  sim.counts = {1e4, 100};
  sim.robot_noise = {0.1, 0.02};
  // The base is never where the setup says.
  sim.effects.robot_base_frame = RigidOffset{{1.5, -2.0, 0.8}, {0.3, -0.2, 0.4}};
  return sim;
}

double median_rms(const ScanCalibration& c) {
  std::vector<double> rms;
  for (const auto& v : c.views)
    if (v.status == ViewStatus::ok) rms.push_back(v.rms_px);
  std::nth_element(rms.begin(), rms.begin() + static_cast<std::ptrdiff_t>(rms.size() / 2), rms.end());
  return rms[rms.size() / 2];
}

TEST(RobotPrior, CombinedPosesReachAHundredthOfADegree) {
  const auto dir = testing::scratch_dir();
  const PandaSetup setup = reference_panda_setup({720, 720, 0.6, 0.6}, 2150, 1360);
  simulate_scan(reference_scan(circular_robot_trajectory(setup, 24), setup), dir);
  const ScanDescription scan = read_scan(dir / "scan.json");
  const ScanCalibration image_only = calibrate_scan(scan, {});
  ScanCalibration c = image_only;
  // The repeatability assumed at first is five times too large: the scan measures its own.
  RobotPriorOptions options;
  options.start_sigma_mm = 0.5;
  options.start_sigma_deg = 0.1;
  const RobotPriorFit prior = combine_with_robot(scan, c, options);
  ASSERT_TRUE(prior.applied) << prior.reason;
  EXPECT_EQ(prior.views, 24);
  const PoseErrors before = compare_with_truth(image_only, dir), after = compare_with_truth(c, dir);
  std::cout << "image alone: across " << before.across_rms_mm * 1000 << " um, along " << before.along_rms_mm * 1000
            << " um, rotation " << before.rotation_rms_deg << " deg RMS\n"
            << "with the robot (measured " << prior.sigma_mm << " mm, " << prior.sigma_deg << " deg): across "
            << after.across_rms_mm * 1000 << " um, along " << after.along_rms_mm * 1000 << " um, rotation "
            << after.rotation_rms_deg << " deg RMS (max " << after.rotation_max_deg << "); median rotation sigma "
            << prior.image_rotation_sigma_deg << " -> " << prior.combined_rotation_sigma_deg << " deg\n";
  // The image alone is photon-limited near 0.011 deg here (test_calibration); the robot's
  // 0.02 deg (0.012 per axis) adds its information: about 0.0095 deg expected.
  EXPECT_LE(after.rotation_rms_deg, 0.01);
  EXPECT_LE(after.rotation_rms_deg, 0.92 * before.rotation_rms_deg);
  // Depth is where the robot helps most (0.058 mm per axis against the image's ~0.12 mm).
  EXPECT_LE(after.along_rms_mm, 0.7 * before.along_rms_mm);
  EXPECT_LE(after.across_rms_mm, 0.01);
  EXPECT_LE(after.across_rms_mm, 1.05 * before.across_rms_mm);
  // The repeatability the scan shows is the simulated one (24 views: about 15 % sampling error).
  EXPECT_NEAR(prior.sigma_mm, 0.1, 0.035);
  EXPECT_NEAR(prior.sigma_deg, 0.02, 0.006);
  // The reported uncertainties shrink, and the poses still fit their images.
  EXPECT_LT(prior.combined_rotation_sigma_deg, 0.9 * prior.image_rotation_sigma_deg);
  EXPECT_LT(c.views[0].translation_sigma_mm[2], 0.7 * image_only.views[0].translation_sigma_mm[2]);
  EXPECT_LE(median_rms(c), 1.1 * median_rms(image_only));
  for (std::size_t v = 0; v < c.views.size(); ++v) {
    ASSERT_TRUE(c.geometry.views[v].P);
    const Eigen::Vector3d X = scan.holder->spheres_mm[7];
    EXPECT_LT((c.geometry.views[v].P->project(X) - c.views[v].P->project(X)).norm(), 1e-9);
  }

  // Too few calibrated views for the model's 12 offsets: nothing changes, and the reason is said.
  ScanCalibration few = image_only;
  for (std::size_t v = 8; v < few.views.size(); ++v) few.views[v].status = ViewStatus::rejected;
  const RobotPriorFit none = combine_with_robot(scan, few);
  EXPECT_FALSE(none.applied);
  EXPECT_NE(none.reason.find("8 calibrated views"), std::string::npos) << none.reason;
  EXPECT_TRUE(few.views[0].T_camera_holder->isApprox(*image_only.views[0].T_camera_holder));
}

struct Outcome {
  RobotPriorFit prior;
  PoseErrors before, after;
};

// A spherical trajectory of 24 views, the holder sagging by up to `sag_deg`.
Outcome spherical_scan(double sag_deg) {
  const auto dir = testing::scratch_dir();
  const PandaSetup setup = reference_panda_setup({720, 720, 0.6, 0.6}, 2150, 1360);
  ScanSimulation sim = reference_scan(spherical_robot_trajectory(setup, random_directions(24, 11)), setup);
  if (sag_deg > 0) sim.effects.holder_sag_deg = sag_deg;
  simulate_scan(sim, dir);
  const ScanDescription scan = read_scan(dir / "scan.json");
  const ScanCalibration image_only = calibrate_scan(scan, {});
  ScanCalibration c = image_only;
  Outcome o;
  o.prior = combine_with_robot(scan, c);
  EXPECT_TRUE(o.prior.applied) << o.prior.reason;
  o.before = compare_with_truth(image_only, dir);
  o.after = compare_with_truth(c, dir);
  std::cout << "spherical, sag " << sag_deg << " deg: measured repeatability " << o.prior.sigma_mm << " mm, " << o.prior.sigma_deg
            << " deg; rotation " << o.before.rotation_rms_deg << " -> " << o.after.rotation_rms_deg << " deg RMS, across "
            << o.before.across_rms_mm * 1000 << " -> " << o.after.across_rms_mm * 1000 << " um; "
            << o.prior.inconsistent_views.size() << " views inconsistent with the robot; median rotation sigma "
            << o.prior.image_rotation_sigma_deg << " -> " << o.prior.combined_rotation_sigma_deg << " deg\n";
  return o;
}

TEST(RobotPrior, HelpsViewsAlongTheHolderAxis) {
  // Views with the holder's axis near the beam see the helix end on: few spheres, often
  // overlapping, in the wall's long shadow. With the tube's ends modelled their image poses hold
  // (0.017 deg RMS over this trajectory; 0.08 deg with an infinitely long tube, from two such
  // views); the robot's prior still adds to them.
  const Outcome o = spherical_scan(0);
  EXPECT_LE(o.before.rotation_rms_deg, 0.025);
  EXPECT_LE(o.after.rotation_rms_deg, 0.8 * o.before.rotation_rms_deg);
  EXPECT_LE(o.after.across_rms_mm, 1.05 * o.before.across_rms_mm);
  EXPECT_NEAR(o.prior.sigma_mm, 0.1, 0.035);
  EXPECT_NEAR(o.prior.sigma_deg, 0.02, 0.006);
}

TEST(RobotPrior, ARobotWorseThanItsModelOnlyWeakensThePrior) {
  // The holder sags towards gravity by up to 0.15 deg, which the robot's model does not know:
  // the poses deviate from it by far more than the repeatability. The scan measures that, and
  // the prior's weight falls with it.
  const Outcome o = spherical_scan(0.15);
  EXPECT_GT(o.prior.sigma_deg, 0.05);
  EXPECT_LE(o.after.rotation_rms_deg, o.before.rotation_rms_deg);
  EXPECT_LE(o.after.across_rms_mm, o.before.across_rms_mm);
}

}  // namespace
}  // namespace ctk

// The diagnosis on simulated scans that each carry one undeclared effect (or none, or one
// outside the vocabulary): the right effect accepted with its size, nothing else.
#include <gtest/gtest.h>

#include <algorithm>

#include "../test_support.hpp"
#include "ctk/calib/diagnosis.hpp"
#include "ctk/calib/robot_prior.hpp"
#include "ctk/geom/trajectory.hpp"
#include "ctk/phantoms/scan_simulation.hpp"
#include "ctk/phantoms/true_scan.hpp"

namespace ctk {
namespace {

constexpr double kDegree = M_PI / 180.0;

ScanSimulation scan_with(int views, bool spherical) {
  ScanSimulation sim;
  sim.setup = reference_panda_setup({720, 720, 0.6, 0.6}, 2150, 1360);
  sim.holder = reference_helix_holder();
  sim.trajectory = spherical ? spherical_robot_trajectory(sim.setup, random_directions(views, 11))
                             : circular_robot_trajectory(sim.setup, views);
  sim.counts = {1e4, 100};
  return sim;
}

struct Outcome {
  ScanDescription scan;
  Diagnosis diagnosis;
  ScanObservations observations;
  nlohmann::json report;
};

Outcome diagnose_scan(const ScanDescription& scan, const DiagnosisOptions& options) {
  const ScanCalibration c = calibrate_scan(scan, {});
  Outcome o;
  o.scan = scan;
  o.observations = observe_scan(scan, c, options);
  o.diagnosis = diagnose(o.observations, options, [](const std::string& s) { std::cout << s << "\n"; });
  o.report = diagnosis_to_json(o.diagnosis, o.observations);
  return o;
}

Outcome run(const ScanSimulation& sim, const DiagnosisOptions& options = {}) {
  const auto dir = testing::scratch_dir();
  simulate_scan(sim, dir);
  return diagnose_scan(read_scan(dir / "scan.json"), options);
}

std::vector<std::string> accepted_names(const Outcome& o) {
  std::vector<std::string> names;
  for (const auto& e : o.report.at("effects"))
    if (e.at("accepted").get<bool>()) names.push_back(e.at("name").get<std::string>());
  return names;
}

const nlohmann::json& accepted_effect(const Outcome& o) {
  for (const auto& e : o.report.at("effects"))
    if (e.at("accepted").get<bool>()) return e;
  throw std::runtime_error("nothing accepted");
}

std::vector<double> numbers(const nlohmann::json& j) { return j.get<std::vector<double>>(); }

void expect_within(const std::vector<double>& found, const std::vector<double>& truth, double relative, double absolute) {
  ASSERT_EQ(found.size(), truth.size());
  for (std::size_t i = 0; i < truth.size(); ++i)
    EXPECT_NEAR(found[i], truth[i], std::max(relative * std::abs(truth[i]), absolute)) << "component " << i;
}

// Calibrating from scratch with the corrected scan and diagnosing again must start where the
// first diagnosis ended ("after"), with nothing more to find.
void expect_recalibration_reproduces_after(const Outcome& o, const DiagnosisOptions& options = {}) {
  write_scan(corrected_scan(o.scan, o.diagnosis), o.scan.folder / "corrected-scan.json");
  const Outcome again = diagnose_scan(read_scan(o.scan.folder / "corrected-scan.json"), options);
  const auto& final_error = o.report.at("final");
  const auto& baseline = again.report.at("baseline");
  std::cout << "after: " << final_error.dump() << "\nrecalibrated with the corrected scan: " << baseline.dump() << "\n";
  EXPECT_NEAR(baseline.at("rms_px").get<double>(), final_error.at("rms_px").get<double>(),
              0.05 * final_error.at("rms_px").get<double>());
  if (final_error.contains("fk_translation_rms_mm")) {
    EXPECT_NEAR(baseline.at("fk_translation_rms_mm").get<double>(), final_error.at("fk_translation_rms_mm").get<double>(),
                std::max(0.01, 0.1 * final_error.at("fk_translation_rms_mm").get<double>()));
  }
  EXPECT_TRUE(accepted_names(again).empty()) << again.report.at("effects").dump();
}

// The thesis' case: the robot's base 1.3 mm off along the beam, 0.05 mm repeatability.
TEST(Diagnosis, RobotBaseOffAlongTheBeam) {
  ScanSimulation sim = scan_with(60, false);
  sim.effects.robot_base_frame = RigidOffset{{0.0, 0.0, 1.3}, {0.0, 0.0, 0.0}};
  sim.robot_noise = {0.05, 0.01};
  DiagnosisOptions options;
  options.robot_sigma_mm = 0.05;
  options.robot_sigma_deg = 0.01;
  const Outcome o = run(sim, options);
  ASSERT_EQ(accepted_names(o), std::vector<std::string>{"robot_base_frame"});
  const auto& e = accepted_effect(o);
  expect_within(numbers(e.at("parameters").at("translation_mm")), {0, 0, 1.3}, 0.1, 0.13);
  // On a joint-7 orbit a mount or joint offset explains the same residual: listed, not guessed.
  EXPECT_FALSE(e.at("confounded_with").empty());
  std::cout << "FK error " << e.at("fk_translation_rms_mm_before") << " -> " << e.at("fk_translation_rms_mm_after") << " mm\n";
  EXPECT_GT(e.at("fk_translation_rms_mm_before").get<double>(), 1.2);
  EXPECT_LE(e.at("fk_translation_rms_mm_after").get<double>(), 0.1);
  EXPECT_FALSE(o.report.at("unexplained").at("structured").get<bool>());

  expect_recalibration_reproduces_after(o, options);
}

TEST(Diagnosis, NothingAcceptedWithoutAnEffect) {
  const Outcome o = run(scan_with(60, false));
  EXPECT_TRUE(accepted_names(o).empty());
  // A joint-7 orbit keeps the holder's tilt: no correlation with time to speak of.
  EXPECT_EQ(o.report.at("time_and_tilt").at("correlation").get<double>(), 0.0);
  EXPECT_FALSE(o.report.at("unexplained").at("structured").get<bool>());
}

TEST(Diagnosis, DisplacedSpheres) {
  ScanSimulation sim = scan_with(60, false);
  sim.effects.sphere_positions = SphereDisplacement{5, 0.2};
  const auto o = run(sim);
  ASSERT_EQ(accepted_names(o), std::vector<std::string>{"sphere_positions"});
  const auto& e = accepted_effect(o);
  // Every significant sphere is one of the displaced ones, each found to within 0.06 mm of its
  // 0.2 mm (the gauge, which keeps the list's centroid, orientation and scale, takes a share).
  const auto spheres = e.at("parameters").at("spheres");
  EXPECT_EQ(spheres.size(), 5u);
  for (const auto& s : spheres) {
    const Eigen::Vector3d d(numbers(s.at("offset_mm")).data());
    EXPECT_NEAR(d.norm(), 0.2, 0.06) << s.dump();
  }
  EXPECT_LT(e.at("rms_px_after").get<double>(), 0.8 * e.at("rms_px_before").get<double>());
  expect_recalibration_reproduces_after(o);
}

TEST(Diagnosis, DetectorIntrinsicsFromTheImagesAndTheRobot) {
  ScanSimulation sim = scan_with(60, false);
  DetectorIntrinsicsError d;
  d.principal_point_error_px = {5, -3};
  d.sdd_error_mm = 20;
  sim.effects.detector_intrinsics = d;
  const Outcome o = run(sim);
  const auto names = accepted_names(o);
  ASSERT_EQ(names.size(), 1u);
  const auto& e = accepted_effect(o);
  if (names[0] == "detector_intrinsics") {
    EXPECT_NEAR(e.at("parameters").at("u0_px").get<double>(), 364.5, 0.5);
    EXPECT_NEAR(e.at("parameters").at("v0_px").get<double>(), 356.5, 0.5);
    EXPECT_NEAR(e.at("parameters").at("source_to_detector_mm").get<double>(), 2170, 2.0);
  } else {
    // Reported as a robot frame only when the detector's own reading is confounded with it.
    EXPECT_NE(e.at("confounded_with").dump().find("detector_intrinsics"), std::string::npos);
  }
  expect_recalibration_reproduces_after(o);
}

TEST(Diagnosis, SourceDrift) {
  ScanSimulation sim = scan_with(60, false);
  sim.effects.source_drift_mm_per_100_views = Eigen::Vector2d(1.0, -0.6);
  const auto o = run(sim);
  ASSERT_EQ(accepted_names(o), std::vector<std::string>{"source_drift"});
  expect_within(numbers(accepted_effect(o).at("parameters").at("drift_mm_per_100_views")), {1.0, -0.6}, 0.1, 0.0);
  expect_recalibration_reproduces_after(o);
}

TEST(Diagnosis, JointOffsetsOnASphericalTrajectory) {
  ScanSimulation sim = scan_with(60, true);
  const panda::Joints offsets{0.002, -0.003, 0.001, 0.004, -0.002, 0.003, 0.002};
  sim.effects.joint_offsets_rad = offsets;
  const auto o = run(sim);
  ASSERT_EQ(accepted_names(o), std::vector<std::string>{"joint_offsets"});
  std::vector<double> deg;
  for (double q : offsets) deg.push_back(q * 180 / M_PI);
  expect_within(numbers(accepted_effect(o).at("parameters").at("offsets_deg")), deg, 0.1, 0.0);
  // Random directions in random order: time and tilt are not confounded.
  std::cout << "time and tilt: " << o.report.at("time_and_tilt").dump() << "\n";
  EXPECT_FALSE(o.report.at("time_and_tilt").at("confounded").get<bool>());
  expect_recalibration_reproduces_after(o);
}

TEST(Diagnosis, HolderMountOnASphericalTrajectory) {
  ScanSimulation sim = scan_with(60, true);
  sim.effects.holder_mount = RigidOffset{{0.5, -0.3, 0.8}, {0.1, 0.2, -0.1}};
  const auto o = run(sim);
  ASSERT_EQ(accepted_names(o), std::vector<std::string>{"holder_mount"});
  const auto& p = accepted_effect(o).at("parameters");
  expect_within(numbers(p.at("translation_mm")), {0.5, -0.3, 0.8}, 0.1, 0.0);
  expect_within(numbers(p.at("rotation_deg")), {0.1, 0.2, -0.1}, 0.1, 0.0);
  expect_recalibration_reproduces_after(o);
}

TEST(Diagnosis, RadialDistortion) {
  ScanSimulation sim = scan_with(60, false);
  sim.effects.detector_distortion = RadialDistortion{2e-8, {380, 340}};
  const auto o = run(sim);
  ASSERT_EQ(accepted_names(o), std::vector<std::string>{"detector_distortion"});
  const auto& e = accepted_effect(o);
  // The holder covers the middle of the detector, where a per-view pose absorbs most of a radial
  // distortion; what is left fixes k1 only loosely: within 30 % here, with its uncertainty.
  const double k1 = e.at("parameters").at("k1_per_px2").get<double>();
  std::cout << "k1 " << k1 << " +- " << e.at("uncertainty").dump() << "\n";
  EXPECT_NEAR(k1, 2e-8, 0.6e-8);

  // The corrected scan declares the distortion (detector.radial_distortion); calibrating with it
  // undistorts the centres.
  ASSERT_TRUE(corrected_scan(o.scan, o.diagnosis).distortion);
  EXPECT_NEAR(corrected_scan(o.scan, o.diagnosis).distortion->k1_per_px2, k1, 1e-15);
  expect_recalibration_reproduces_after(o);
}

// The thesis' second case: one sphere 0.3 mm off its declared place (0.8 px in the image: the
// calibration drops it as an outlier in every view, and the diagnosis takes it back because it is
// off in every view) and a radially distorting detector (1.9 px at 360 px from the centre). Both
// accepted, the sphere first, nothing else; the RMS before and after each.
TEST(Diagnosis, DisplacedSphereBesideRadialDistortion) {
  ScanSimulation sim = scan_with(60, false);
  sim.effects.sphere_positions = SphereDisplacement{1, 0.3};
  sim.effects.detector_distortion = RadialDistortion{4e-8, {380, 340}};
  const auto o = run(sim);
  const auto names = accepted_names(o);
  ASSERT_EQ(names, (std::vector<std::string>{"sphere_positions", "detector_distortion"}));
  for (const auto& e : o.report.at("effects")) {
    std::cout << e.at("name") << (e.at("accepted").get<bool>() ? " accepted" : " not accepted") << ": RMS "
              << e.at("rms_px_before") << " -> " << e.at("rms_px_after") << " px, held out " << e.at("heldout_rms_px_before")
              << " -> " << e.at("heldout_rms_px_after") << "\n";
    if (e.at("name") == "sphere_positions") {
      const auto spheres = e.at("parameters").at("spheres");
      ASSERT_EQ(spheres.size(), 1u);
      EXPECT_NEAR(Eigen::Vector3d(numbers(spheres[0].at("offset_mm")).data()).norm(), 0.3, 0.06);
    }
    if (e.at("name") == "detector_distortion") {
      std::cout << "k1 " << e.at("parameters").at("k1_per_px2") << " +- " << e.at("uncertainty").at("k1_per_px2") << "\n";
      EXPECT_NEAR(e.at("parameters").at("k1_per_px2").get<double>(), 4e-8, 1.2e-8);
    }
  }
  std::cout << "baseline " << o.report.at("baseline").at("rms_px") << " px -> final " << o.report.at("final").at("rms_px")
            << " px\n";
  EXPECT_LT(o.report.at("final").at("rms_px").get<double>(), 0.6 * o.report.at("baseline").at("rms_px").get<double>());
  expect_recalibration_reproduces_after(o);
}

// Outside the vocabulary: the holder sags under its weight, turning towards gravity by up to
// 0.15 deg depending on its orientation (a spherical trajectory turns it every way). No named
// effect may take the blame; the report must say structure is left, and where.
TEST(Diagnosis, HolderSagIsStructuredAndAttributedToNothing) {
  ScanSimulation sim = scan_with(60, true);
  sim.effects.holder_sag_deg = 0.15;
  const auto o = run(sim);
  EXPECT_TRUE(accepted_names(o).empty()) << o.report.at("effects").dump();
  EXPECT_TRUE(o.report.at("unexplained").at("structured").get<bool>());
  const std::string note = o.report.at("unexplained").at("note").get<std::string>();
  std::cout << note << "\n";
  EXPECT_NE(note.find("gravity"), std::string::npos);
}

// On a cap of directions (5 to 90 deg from the beam, spun about the holder axis) a sag's mean is
// nearly a constant turn, which a base offset takes up in part: with the base truly 0.8 mm off as
// well, the base offset is accepted at its size, the sag is found as a load that follows gravity
// (its turn at a horizontal holder recovered) and reported as structure, and nothing else.
TEST(Diagnosis, AHolderSaggingOnACapIsALoadBesideTheBaseOffset) {
  ScanSimulation sim = scan_with(60, true);
  sim.trajectory = spherical_robot_trajectory(sim.setup, spinning_cap_directions(60, 5 * kDegree, 90 * kDegree));
  sim.effects.holder_sag_deg = 0.15;
  sim.effects.robot_base_frame = RigidOffset{{0.3, -0.5, 0.5}, {0.0, 0.0, 0.0}};
  sim.robot_noise = {0.05, 0.01};
  DiagnosisOptions options;
  options.robot_sigma_mm = 0.05;
  options.robot_sigma_deg = 0.01;
  const Outcome o = run(sim, options);
  ASSERT_EQ(accepted_names(o), std::vector<std::string>{"robot_base_frame"}) << o.report.at("effects").dump();
  const auto& e = accepted_effect(o);
  const auto found = numbers(e.at("parameters").at("translation_mm"));
  const auto sigma = numbers(e.at("uncertainty").at("translation_mm"));
  const std::vector<double> truth{0.3, -0.5, 0.5};
  for (int i = 0; i < 3; ++i)
    EXPECT_NEAR(found[static_cast<std::size_t>(i)], truth[static_cast<std::size_t>(i)],
                std::max(0.1 * 0.8, 3 * sigma[static_cast<std::size_t>(i)]))
        << "component " << i;
  ASSERT_EQ(o.diagnosis.outside.size(), 1u);
  const EffectFinding& load = o.diagnosis.outside.front();
  EXPECT_EQ(load.effect, Effect::gravity_load);
  const double turn_deg = load.parameters.gravity[0] / kDegree;
  const double turn_sigma_deg = std::sqrt(load.covariance(0, 0)) / kDegree;
  std::cout << "sag turn " << turn_deg << " +- " << turn_sigma_deg << " deg (truth 0.15), shift " << load.parameters.gravity[1]
            << " mm (truth 0)\n";
  EXPECT_NEAR(turn_deg, 0.15, std::max(0.015, 3 * turn_sigma_deg));
  EXPECT_TRUE(o.report.at("unexplained").at("structured").get<bool>());
  const std::string note = o.report.at("unexplained").at("note").get<std::string>();
  EXPECT_NE(note.find("follows gravity"), std::string::npos);
  // Swept from the axis outwards, the cap tilts the holder further with every view: a drift in
  // time would look alike, and the report says so.
  std::cout << "time and tilt: " << o.report.at("time_and_tilt").dump() << "\n";
  EXPECT_TRUE(o.report.at("time_and_tilt").at("confounded").get<bool>());
  EXPECT_NE(note.find("source_drift"), std::string::npos) << note;
}

// A robot that repeats to 0.02 mm and 0.005 deg, finer than the image resolves a pose's tilt:
// the base offset is found, and nothing beside it (the mount shift along the flange axis that an
// orbit cannot tell from the base's stays at zero, and a joint offset that only repeats the base
// buys no held-out chi-square); the repeatability is not measured as zero.
TEST(Diagnosis, AFineRobotGetsItsBaseOffsetAndNothingElse) {
  ScanSimulation sim = scan_with(60, false);
  sim.effects.robot_base_frame = RigidOffset{{0.4, -0.27, 0.8}, {0.0, 0.0, 0.0}};
  sim.robot_noise = {0.02, 0.005};
  const auto dir = testing::scratch_dir();
  simulate_scan(sim, dir);
  const ScanDescription scan = read_scan(dir / "scan.json");
  ScanCalibration c = calibrate_scan(scan, {});
  ScanCalibration measured = c;
  const RobotPriorFit prior = combine_with_robot(scan, measured);
  ASSERT_TRUE(prior.applied) << prior.reason;
  std::cout << "repeatability measured " << prior.sigma_mm << " mm, " << prior.sigma_deg << " deg\n";
  EXPECT_GT(prior.sigma_deg, 0.001);
  EXPECT_LT(prior.sigma_deg, 0.02);
  DiagnosisOptions options;
  options.robot_sigma_mm = prior.sigma_mm;
  options.robot_sigma_deg = prior.sigma_deg;
  const Outcome o = diagnose_scan(scan, options);
  ASSERT_EQ(accepted_names(o), std::vector<std::string>{"robot_base_frame"}) << o.report.at("effects").dump();
  expect_within(numbers(accepted_effect(o).at("parameters").at("translation_mm")), {0.4, -0.27, 0.8}, 0.05, 0.05);
  EXPECT_FALSE(o.report.at("unexplained").at("structured").get<bool>()) << o.report.at("unexplained").dump();
}

// Outside the vocabulary: a sphere comes loose and moves 0.4 mm during the scan. Its average
// place may be taken as a misplaced sphere, but the report must say the place changes with the
// scan's progress, and name the sphere.
TEST(Diagnosis, ASphereThatMovesDuringTheScanIsStructure) {
  ScanSimulation sim = scan_with(60, false);
  sim.effects.moving_sphere_mm = 0.4;
  sim.robot_noise = {0.05, 0.01};
  const auto o = run(sim);
  for (const auto& name : accepted_names(o)) EXPECT_EQ(name, "sphere_positions");
  EXPECT_TRUE(o.report.at("unexplained").at("structured").get<bool>());
  const std::string note = o.report.at("unexplained").at("note").get<std::string>();
  std::cout << note << "\n";
  const TrueScan truth = make_true_scan(sim);
  EXPECT_NE(note.find("by sphere over the scan"), std::string::npos);
  EXPECT_NE(note.find("sphere " + std::to_string(truth.moving_sphere) + " moves"), std::string::npos);
}

}  // namespace
}  // namespace ctk

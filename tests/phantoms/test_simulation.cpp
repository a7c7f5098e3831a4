// The simulator: photon statistics, the numerical IK behind spherical joint logs, and the central
// promise that the truth it writes explains its images — sphere blobs sit where the true
// matrices (and the true distortion) put the sphere centres, whatever undeclared effects are on.
#include <gtest/gtest.h>

#include <random>

#include "../test_support.hpp"
#include "ctk/geom/nominal_geometry.hpp"
#include "ctk/geom/scan.hpp"
#include "ctk/geom/trajectory.hpp"
#include "ctk/phantoms/builtin_phantoms.hpp"
#include "ctk/phantoms/panda_ik.hpp"
#include "ctk/phantoms/scan_simulation.hpp"
#include "ctk/phantoms/simulation_run.hpp"

namespace ctk {
namespace {

constexpr double kDegree = M_PI / 180.0;

TEST(DetectorResponse, CountsArePoissonInMeanAndVariance) {
  const CountsModel model{0, 100};
  std::mt19937_64 rng(11);
  for (double mean : {3.0, 40.0, 700.0, 5000.0}) {
    const int n = 500;
    Image counts{n, n, std::vector<float>(static_cast<std::size_t>(n * n), static_cast<float>(model.dark_counts + mean))};
    draw_counts(counts, model, rng);
    double sum = 0, sum2 = 0;
    for (float c : counts.pixels) {
      const double x = c - model.dark_counts;
      sum += x;
      sum2 += x * x;
    }
    const double m = sum / counts.pixels.size(), var = sum2 / counts.pixels.size() - m * m;
    EXPECT_NEAR(m, mean, 0.02 * mean) << mean;
    EXPECT_NEAR(var, mean, 0.02 * mean) << mean;
  }
}

TEST(PandaIk, ReachesAPoseTheArmCanTake) {
  std::mt19937_64 rng(3);
  const auto& limits = panda::joint_limits();
  for (int trial = 0; trial < 10; ++trial) {
    panda::Joints q;
    for (std::size_t j = 0; j < q.size(); ++j)
      q[j] = std::uniform_real_distribution<double>(0.8 * limits[j].lower_rad + 0.2 * limits[j].upper_rad,
                                                    0.2 * limits[j].lower_rad + 0.8 * limits[j].upper_rad)(rng);
    const Rigid target = panda::forward_kinematics(q);
    // Start from a perturbation of the answer: the IK must converge, not guess.
    panda::Joints start = q;
    for (double& x : start) x += std::normal_distribution<double>(0, 0.15)(rng);
    const IkSolution ik = solve_panda_ik(target, start);
    ASSERT_TRUE(ik.reached) << trial << ": " << ik.position_error_mm << " mm, " << ik.rotation_error_deg << " deg";
    EXPECT_TRUE(panda::joints_out_of_limits(ik.q).empty());
  }
}

TEST(RobotTrajectory, SphericalViewsPutTheHolderAtTheIsocentreLookingAlongEachDirection) {
  const PandaSetup setup = reference_panda_setup({360, 360, 1.2, 1.2}, 2150, 1360);
  const HealpixSphere sphere(2);
  const auto views = spherical_robot_trajectory(setup, sphere.directions());
  ASSERT_EQ(views.size(), 48u);
  int reached = 0;
  for (const PlannedView& v : views) {
    if (!v.joints) {
      EXPECT_FALSE(v.note.empty());
      continue;
    }
    ++reached;
    EXPECT_TRUE(panda::joints_out_of_limits(*v.joints).empty());
    const Rigid T = setup.T_camera_base * panda::forward_kinematics(*v.joints) * setup.T_flange_holder;
    EXPECT_LT((T.translation() - Eigen::Vector3d(0, 0, 1360)).norm(), 1e-3);
    // The beam (+z) seen from the holder is the wanted direction.
    EXPECT_LT(angular_distance_rad(T.linear().transpose() * Eigen::Vector3d::UnitZ(), v.direction), 1e-6);
  }
  EXPECT_GE(reached, 24) << "fewer than half of the directions reachable";
}

ScanSimulation small_circular_scan(int views) {
  ScanSimulation sim;
  sim.setup = reference_panda_setup({720, 720, 0.6, 0.6}, 2150, 1360);
  sim.holder = reference_helix_holder();
  sim.trajectory = circular_robot_trajectory(sim.setup, views);
  sim.output = SimulatedOutput::line_integrals;
  return sim;
}

TEST(ScanSimulation, WithoutEffectsOrNoiseTheTruthIsTheDeclaredGeometry) {
  ScanSimulation sim = small_circular_scan(5);
  sim.robot_noise = {0, 0};
  const TrueScan truth = make_true_scan(sim);
  ASSERT_EQ(truth.acquired_views(), 5);
  ScanDescription declared;
  declared.detector = sim.setup.detector;
  declared.principal_point_px = sim.setup.principal_point_px;
  declared.source_to_detector_mm = sim.setup.source_to_detector_mm;
  PandaPoseSource panda{"", sim.setup.T_camera_base, sim.setup.T_flange_holder, {}};
  for (int v = 0; v < 5; ++v) panda.joints.add(v, *sim.trajectory[static_cast<std::size_t>(v)].joints);
  declared.panda = panda;
  declared.projections.count = 5;
  const auto nominal = nominal_views(declared);
  for (int v = 0; v < 5; ++v)
    EXPECT_LT(max_abs_difference(*truth.views[static_cast<std::size_t>(v)].P, *nominal[static_cast<std::size_t>(v)].P), 1e-9);
}

// Intensity-weighted centroid of a blob within `radius` of `guess` (background is zero here).
Eigen::Vector2d centroid(const Image& im, const Eigen::Vector2d& guess, double radius) {
  Eigen::Vector2d sum(0, 0);
  double weight = 0;
  for (int r = static_cast<int>(guess.y() - radius) - 1; r <= static_cast<int>(guess.y() + radius) + 1; ++r)
    for (int c = static_cast<int>(guess.x() - radius) - 1; c <= static_cast<int>(guess.x() + radius) + 1; ++c) {
      if ((Eigen::Vector2d(c, r) - guess).norm() > radius) continue;
      const double w = im.pixels[static_cast<std::size_t>(r * im.cols + c)];
      sum += w * Eigen::Vector2d(c, r);
      weight += w;
    }
  return sum / weight;
}

TEST(ScanSimulation, TrueMatricesPutEverySphereOnItsBlobUnderUndeclaredEffects) {
  const auto dir = testing::scratch_dir();
  ScanSimulation sim = small_circular_scan(4);
  sim.with_holder = false;  // spheres alone, so a plain centroid needs no background model
  sim.sample = Phantom{"spheres", {}};
  for (const auto& s : sim.holder.spheres_mm)
    sim.sample.primitives.push_back(Primitive::sphere(s, 0.5 * sim.holder.sphere_diameter_mm, material::aluminium));
  SimulationEffects& e = sim.effects;
  e.detector_intrinsics = DetectorIntrinsicsError{20.0, {3.0, -2.0}, {1.5, -1.0}};
  e.detector_distortion = RadialDistortion{4e-9, {350.0, 372.0}};
  e.robot_base_frame = RigidOffset{{1.0, -2.0, 0.5}, {0.1, 0.0, -0.05}};
  e.holder_mount = RigidOffset{{0.3, 0.2, -0.4}, {0.0, 0.0, 0.5}};
  e.joint_offsets_rad = panda::Joints{0.05 * kDegree,  -0.03 * kDegree, 0.02 * kDegree, 0.04 * kDegree,
                                      -0.05 * kDegree, 0.03 * kDegree,  0.1 * kDegree};
  e.source_drift_mm_per_100_views = Eigen::Vector2d(3.0, 1.0);
  const SimulationReport report = simulate_scan(sim, dir);
  ASSERT_EQ(report.views_acquired, 4);

  const ScanDescription scan = read_scan(dir / "scan.json");
  const Geometry truth = read_geometry(dir / "truth-geometry.json");
  const Geometry nominal = nominal_geometry(scan);
  const double magnification = 2150.0 / 1360.0;
  const double blob_radius = 0.5 * 2.0 * magnification / 0.6;
  int measured = 0;
  double worst = 0, nominal_error = 0;
  for (int v = 0; v < 4; ++v) {
    const Image im = read_image(scan.projection_path(v), 720, 720);
    const ProjectionMatrix& P = *truth.views[static_cast<std::size_t>(v)].P;
    std::vector<Eigen::Vector2d> where;
    for (const auto& s : sim.holder.spheres_mm) where.push_back(e.detector_distortion->measured_from_ideal(P.project(s)));
    for (std::size_t k = 0; k < where.size(); ++k) {
      bool isolated = scan.detector.contains(where[k], 10.0);
      for (std::size_t j = 0; j < where.size(); ++j)
        if (j != k && (where[j] - where[k]).norm() < 2 * blob_radius + 5) isolated = false;
      if (!isolated) continue;
      const Eigen::Vector2d c = centroid(im, where[k], blob_radius + 2);
      worst = std::max(worst, (c - where[k]).norm());
      nominal_error =
          std::max(nominal_error, (nominal.views[static_cast<std::size_t>(v)].P->project(sim.holder.spheres_mm[k]) - c).norm());
      ++measured;
    }
  }
  std::cout << "isolated spheres " << measured << ", worst " << worst << " px, nominal " << nominal_error << " px\n";
  EXPECT_GT(measured, 60);
  EXPECT_LT(worst, 0.05) << "px, over " << measured << " isolated spheres";
  // And the effects are undeclared: the scan file's nominal geometry misses by pixels.
  EXPECT_GT(nominal_error, 3.0);
}

// Outside the vocabulary: a focal spot that wanders twice over the scan without a trend, and a
// sphere that moves from its place at the first view to its end offset at the last.
TEST(ScanSimulation, AWanderingSourceAndAMovingSphereFollowTheScansProgress) {
  ScanSimulation sim = small_circular_scan(9);
  sim.robot_noise = {0, 0};
  sim.effects.source_wobble_mm = Eigen::Vector2d(0.4, -0.2);
  sim.effects.moving_sphere_mm = 0.5;
  const TrueScan truth = make_true_scan(sim);
  ASSERT_GE(truth.moving_sphere, 0);
  EXPECT_NEAR(truth.moving_sphere_end_mm.norm(), 0.5, 1e-12);
  Eigen::Vector2d sum(0, 0);
  for (std::size_t v = 0; v < truth.views.size(); ++v) {
    const TrueView& view = truth.views[v];
    const double c = std::cos(4 * M_PI * static_cast<double>(v) / 9.0);
    EXPECT_NEAR(view.source_offset_mm.x(), 0.4 * c, 1e-12);
    EXPECT_NEAR(view.source_offset_mm.y(), -0.2 * c, 1e-12);
    sum += view.source_offset_mm.head<2>();
    ASSERT_TRUE(view.holder.has_value());
    for (std::size_t k = 0; k < truth.holder.spheres_mm.size(); ++k) {
      const Eigen::Vector3d moved = view.holder->spheres_mm[k] - truth.holder.spheres_mm[k];
      const Eigen::Vector3d expected = static_cast<int>(k) == truth.moving_sphere
                                           ? Eigen::Vector3d((v / 8.0) * truth.moving_sphere_end_mm)
                                           : Eigen::Vector3d::Zero();
      EXPECT_LT((moved - expected).norm(), 1e-12) << "view " << v << ", sphere " << k;
    }
  }
  EXPECT_LT(sum.norm(), 1e-12);  // no mean for an offset to take up
  const nlohmann::json j = truth_to_json(sim, truth, "truth-geometry.json");
  EXPECT_EQ(j.at("effects").at("moving_sphere").at("index").get<int>(), truth.moving_sphere);
  EXPECT_EQ(j.at("effects").at("source_wobble").at("amplitude_mm").get<std::vector<double>>(), (std::vector<double>{0.4, -0.2}));
}

TEST(ScanSimulation, CountsScanHasFlatDarkAndOpenBeamAtTheFlatLevel) {
  const auto dir = testing::scratch_dir();
  ScanSimulation sim = small_circular_scan(2);
  sim.setup = reference_panda_setup({96, 80, 4.5, 4.5}, 2150, 1360);
  sim.trajectory = circular_robot_trajectory(sim.setup, 2);
  sim.output = SimulatedOutput::counts;
  sim.counts = {20000, 150};
  sim.effects.false_blobs_per_view = 3;
  simulate_scan(sim, dir);
  const ScanDescription scan = read_scan(dir / "scan.json");
  ASSERT_EQ(scan.projections.kind, ProjectionKind::counts);
  const Image flat = read_image(scan.resolve(scan.projections.flat.front()), 96, 80);
  const Image dark = read_image(scan.resolve(scan.projections.dark.front()), 96, 80);
  EXPECT_EQ(flat.pixels[0], 20150.0f);
  EXPECT_EQ(dark.pixels[0], 150.0f);
  const Image im = read_image(scan.projection_path(1), 96, 80);
  // The top-left corner is open beam in this geometry (holder centred, 432 mm wide field).
  double sum = 0;
  for (int r = 0; r < 8; ++r)
    for (int c = 0; c < 8; ++c) sum += im.pixels[static_cast<std::size_t>(r * 96 + c)] - 150.0;
  EXPECT_NEAR(sum / 64, 20000.0, 4 * std::sqrt(20000.0 / 64));
  const nlohmann::json truth = read_json_file(dir / "truth.json");
  EXPECT_EQ(truth.at("effects").at("false_blobs").at("blobs").size(), 6u);
  EXPECT_EQ(scan.panda->joints.rows().size(), 2u);
}

// The lab's nuisances, as stated: scatter raises the open beam by its fraction of the (here
// nearly open) signal; lag mixes in the view before; the robot's two landing places lie the
// stated distance apart; a droop sinks the flange by the stated amount per metre of reach.
TEST(ScanSimulation, LabNuisancesAreWhatTheyClaim) {
  ScanSimulation sim = small_circular_scan(4);
  sim.setup = reference_panda_setup({96, 80, 4.5, 4.5}, 2150, 1360);
  sim.trajectory = circular_robot_trajectory(sim.setup, 4);
  sim.output = SimulatedOutput::counts;
  sim.counts = {60000, 0};
  sim.robot_noise = {0, 0};
  const Phantom phantom = simulated_phantom(sim, sim.holder);
  const RenderOptions render = simulated_render_options(sim);
  const TrueScan plain = make_true_scan(sim);
  auto corner_mean = [](const Image& im) {
    double sum = 0;
    for (int r = 0; r < 8; ++r)
      for (int c = 0; c < 8; ++c) sum += im.pixels[static_cast<std::size_t>(r * im.cols + c)];
    return sum / 64;
  };
  const double open = corner_mean(simulated_image(sim, phantom, plain.views[1], render));
  ScanSimulation scattered = sim;
  scattered.effects.scatter_fraction = 0.08;
  const double raised = corner_mean(simulated_image(scattered, phantom, plain.views[1], render));
  EXPECT_NEAR(open, 60000, 4 * std::sqrt(60000.0 / 64));
  // The corner sees mostly open beam from afar: between 0.06 and 0.08 of the flat more.
  EXPECT_GT(raised / open - 1, 0.06);
  EXPECT_LT(raised / open - 1, 0.081);

  // Lag of a half, noise made negligible: the image is the mean of this view's and the previous one's.
  ScanSimulation lagging = sim;
  lagging.counts = {6e4, 0};
  lagging.effects.detector_lag = 0.5;
  ScanSimulation plain_counts = lagging;
  plain_counts.effects.detector_lag = 0.0;  // the nuisance path, no lag
  const Image mixed = simulated_image(lagging, phantom, plain.views[2], render, nullptr, &plain.views[1]);
  const Image now = simulated_image(plain_counts, phantom, plain.views[2], render);
  const Image before = simulated_image(plain_counts, phantom, plain.views[1], render);
  double worst = 0, changed = 0;
  for (std::size_t i = 0; i < mixed.pixels.size(); ++i) {
    const double expected = 0.5 * (now.pixels[i] + before.pixels[i]);
    worst = std::max(worst, std::abs(mixed.pixels[i] - expected) / std::sqrt(std::max(expected, 1.0)));
    changed = std::max(changed, std::abs(double(now.pixels[i]) - before.pixels[i]));
  }
  EXPECT_GT(changed, 1000.0) << "the two views must differ for the test to mean anything";
  EXPECT_LT(worst, 6.0) << "beyond Poisson noise of the mixed mean";

  ScanSimulation clustered = sim;
  clustered.effects.robot_clusters_mm = 0.3;
  clustered.trajectory = circular_robot_trajectory(sim.setup, 40);
  const TrueScan two = make_true_scan(clustered);
  const TrueScan none = make_true_scan([&] {
    ScanSimulation s = clustered;
    s.effects.robot_clusters_mm.reset();
    return s;
  }());
  ScanSimulation drooping = sim;
  drooping.effects.robot_droop_mm_per_m = 0.5;
  const TrueScan drooped = make_true_scan(drooping);
  int near = 0, far = 0;
  for (std::size_t v = 0; v < two.views.size(); ++v) {
    // Holder offsets between the scans, in the flange frame (the noise sits between flange and holder).
    const Eigen::Matrix3d camera_flange =
        clustered.setup.T_camera_base.linear() * panda::forward_kinematics(*clustered.trajectory[v].joints).linear();
    const Eigen::Vector3d d =
        camera_flange.transpose() * (two.views[v].T_camera_holder->translation() - none.views[v].T_camera_holder->translation());
    EXPECT_NEAR(d.norm(), 0.15, 1e-9) << v;
    (d.dot(Eigen::Vector3d(1, 2, 3)) > 0 ? near : far) += 1;
  }
  EXPECT_GT(near, 5);
  EXPECT_GT(far, 5);
  for (std::size_t v = 0; v < drooped.views.size(); ++v) {
    const Rigid base_flange = panda::forward_kinematics(*drooping.trajectory[v].joints);
    const double reach_m = base_flange.translation().head<2>().norm() * 1e-3;
    const Eigen::Vector3d shift = drooped.views[v].T_camera_holder->translation() - plain.views[v].T_camera_holder->translation();
    const Eigen::Vector3d expected = sim.setup.T_camera_base.linear() * Eigen::Vector3d(0, 0, -0.5 * reach_m);
    EXPECT_LT((shift - expected).norm(), 1e-9) << v;
  }
}

}  // namespace
}  // namespace ctk

namespace ctk {
namespace {

TEST(SimulationRequest, ChecksItselfAndNamesUnknownEffects) {
  EXPECT_NO_THROW(SimulationRequest{}.validate());
  testing::expect_option_refused(
      SimulationRequest{}, [](auto& r) { r.views = 0; }, "SimulationRequest.views");
  testing::expect_option_refused(
      SimulationRequest{}, [](auto& r) { r.nside = 0; }, "SimulationRequest.nside");
  testing::expect_option_refused(
      SimulationRequest{}, [](auto& r) { r.cap_min_deg = 50, r.cap_max_deg = 40; }, "SimulationRequest.cap_min_deg");
  testing::expect_option_refused(
      SimulationRequest{}, [](auto& r) { r.sod_mm = 3000; }, "SimulationRequest.sod_mm");
  testing::expect_option_refused(
      SimulationRequest{}, [](auto& r) { r.supersampling = 0; }, "SimulationRequest.supersampling");
  testing::expect_option_refused(
      SimulationRequest{}, [](auto& r) { r.kvp = 10.0; }, "SimulationRequest.kvp");
  testing::expect_option_refused(
      SimulationRequest{}, [](auto& r) { r.trajectory = "helical"; }, "SimulationRequest.trajectory");
  // Effects by name: the values land where the simulator reads them; a misspelt one is refused.
  const Detector detector{100, 80, 1, 1};
  const SimulationEffects e = simulation_effects_from_json(
      {{"base_translation_mm", {0.5, 0, 1}}, {"source_drift_mm", {0.4, -0.2}}, {"distortion_k1", 2e-8}}, detector);
  ASSERT_TRUE(e.robot_base_frame && e.source_drift_mm_per_100_views && e.detector_distortion);
  EXPECT_EQ(e.robot_base_frame->translation_mm, Eigen::Vector3d(0.5, 0, 1));
  EXPECT_EQ(e.detector_distortion->centre_px, detector.centre_px());
  EXPECT_FALSE(e.holder_mount);
  EXPECT_THROW(simulation_effects_from_json({{"base_translation", {0, 0, 1}}}, detector), std::invalid_argument);
  EXPECT_THROW(simulation_effects_from_json({{"source_drift_mm", {0.4}}}, detector), std::invalid_argument);
}

}  // namespace
}  // namespace ctk

// libplan's and the phantoms' options structs check themselves: the defaults pass; each field
// out of its range is refused, naming the struct and the field, before any work.
#include <gtest/gtest.h>

#include <string>

#include "../test_support.hpp"
#include "ctk/phantoms/render.hpp"
#include "ctk/plan/absorber_segmentation.hpp"
#include "ctk/plan/edge_tangency.hpp"
#include "ctk/plan/incremental_reconstruction.hpp"
#include "ctk/plan/plan_trajectory.hpp"
#include "ctk/plan/simulated_planning_run.hpp"
#include "ctk/plan/view_planner.hpp"

namespace ctk {
namespace {

TEST(OptionsValidation, PlannerOptions) {
  EXPECT_NO_THROW(PlannerOptions{}.validate());
  testing::expect_option_refused(
      PlannerOptions{}, [](auto& o) { o.candidate_nside = 0; }, "PlannerOptions.candidate_nside");
  testing::expect_option_refused(
      PlannerOptions{}, [](auto& o) { o.planned_views = 0; }, "PlannerOptions.planned_views");
  testing::expect_option_refused(
      PlannerOptions{}, [](auto& o) { o.damage_exponent = -1; }, "PlannerOptions.damage_exponent");
  testing::expect_option_refused(
      PlannerOptions{}, [](auto& o) { o.spread_exponent = 0; }, "PlannerOptions.spread_exponent");
  testing::expect_option_refused(
      PlannerOptions{}, [](auto& o) { o.widest_gap_fraction = 1.5; }, "PlannerOptions.widest_gap_fraction");
  testing::expect_option_refused(
      PlannerOptions{}, [](auto& o) { o.edge_tangency_weight = -0.1; }, "PlannerOptions.edge_tangency_weight");
  testing::expect_option_refused(
      PlannerOptions{}, [](auto& o) { o.damage_floor_mm = 0; }, "PlannerOptions.damage_floor_mm");
  testing::expect_option_refused(
      PlannerOptions{}, [](auto& o) { o.unreachable_radius_deg = 180; }, "PlannerOptions.unreachable_radius_deg");
  // The planner checks before any work.
  PlannerOptions bad;
  bad.candidate_nside = 0;
  EXPECT_THROW(ViewPlanner{bad}, std::invalid_argument);
}

TEST(OptionsValidation, IncrementalOptions) {
  EXPECT_NO_THROW(IncrementalOptions{}.validate());
  testing::expect_option_refused(
      IncrementalOptions{}, [](auto& o) { o.binning = 0; }, "IncrementalOptions.binning");
  testing::expect_option_refused(
      IncrementalOptions{}, [](auto& o) { o.first_update_iterations = 0; }, "IncrementalOptions.first_update_iterations");
  testing::expect_option_refused(
      IncrementalOptions{}, [](auto& o) { o.iterations_per_update = 0; }, "IncrementalOptions.iterations_per_update");
  testing::expect_option_refused(
      IncrementalOptions{}, [](auto& o) { o.lambda = -0.1; }, "IncrementalOptions.lambda");
}

TEST(OptionsValidation, SegmentationOptions) {
  EXPECT_NO_THROW(SegmentationOptions{}.validate());
  testing::expect_option_refused(
      SegmentationOptions{}, [](auto& o) { o.region.radius_mm = 0; }, "SegmentationOptions.region.radius_mm");
  testing::expect_option_refused(
      SegmentationOptions{}, [](auto& o) { o.region.half_height_mm = -1; }, "SegmentationOptions.region.half_height_mm");
  testing::expect_option_refused(
      SegmentationOptions{}, [](auto& o) { o.wall_inner_mm = 0; }, "SegmentationOptions.wall_inner_mm");
  testing::expect_option_refused(
      SegmentationOptions{}, [](auto& o) { o.wall_outer_mm = 20; }, "SegmentationOptions.wall_outer_mm");
  testing::expect_option_refused(
      SegmentationOptions{}, [](auto& o) { o.times_wall = 0; }, "SegmentationOptions.times_wall");
  testing::expect_option_refused(
      SegmentationOptions{}, [](auto& o) { o.min_voxels = 0; }, "SegmentationOptions.min_voxels");
}

TEST(OptionsValidation, EdgeTangencyOptions) {
  EXPECT_NO_THROW(EdgeTangencyOptions{}.validate());
  testing::expect_option_refused(
      EdgeTangencyOptions{}, [](auto& o) { o.tangent_width_deg = 90; }, "EdgeTangencyOptions.tangent_width_deg");
  testing::expect_option_refused(
      EdgeTangencyOptions{}, [](auto& o) { o.normal_nside = 0; }, "EdgeTangencyOptions.normal_nside");
}

TEST(OptionsValidation, PlanningOptions) {
  PlanningOptions good;
  good.coarse_volume = VolumeLayout::centred({8, 8, 8}, Eigen::Vector3d::Constant(2.0));
  EXPECT_NO_THROW(good.validate());
  testing::expect_option_refused(
      good, [](auto& o) { o.scout_nside = 0; }, "PlanningOptions.scout_nside");
  testing::expect_option_refused(
      good, [](auto& o) { o.views = 0; }, "PlanningOptions.views");
  testing::expect_option_refused(
      good, [](auto& o) { o.max_attempts = -1; }, "PlanningOptions.max_attempts");
  testing::expect_option_refused(
      good, [](auto& o) { o.coarse_volume.size[1] = 0; }, "PlanningOptions.coarse_volume.size");
  testing::expect_option_refused(
      good, [](auto& o) { o.coarse_volume.voxel_mm.z() = 0; }, "PlanningOptions.coarse_volume.voxel_mm");
  // Its parts are checked with it, each naming its own field.
  testing::expect_option_refused(
      good, [](auto& o) { o.planner.planned_views = 0; }, "PlannerOptions.planned_views");
  testing::expect_option_refused(
      good, [](auto& o) { o.reconstruction.binning = 0; }, "IncrementalOptions.binning");
  testing::expect_option_refused(
      good, [](auto& o) { o.segmentation.times_wall = 0; }, "SegmentationOptions.times_wall");
  testing::expect_option_refused(
      good, [](auto& o) { o.edge_tangency.normal_nside = 0; }, "EdgeTangencyOptions.normal_nside");
  testing::expect_option_refused(
      good, [](auto& o) { o.calibration.min_spheres = 3; }, "CalibrationOptions.min_spheres");
}

TEST(OptionsValidation, RenderOptions) {
  EXPECT_NO_THROW(RenderOptions{}.validate());
  testing::expect_option_refused(
      RenderOptions{}, [](auto& o) { o.supersampling = 0; }, "RenderOptions.supersampling");
  testing::expect_option_refused(
      RenderOptions{},
      [](auto& o) {
        o.distortion = RadialDistortion{std::nan(""), {0, 0}};
      },
      "RenderOptions.distortion.k1_per_px2");
  testing::expect_option_refused(
      RenderOptions{}, [](auto& o) { o.spectrum = XraySpectrum{}; }, "RenderOptions.spectrum.bins");
}

TEST(OptionsValidation, PlanRequests) {
  EXPECT_NO_THROW(PlanRequest{}.validate());
  testing::expect_option_refused(
      PlanRequest{}, [](auto& o) { o.views = 1; }, "PlanRequest.views");
  testing::expect_option_refused(
      PlanRequest{}, [](auto& o) { o.coarse_size = 4; }, "PlanRequest.coarse_size");
  testing::expect_option_refused(
      PlanRequest{}, [](auto& o) { o.coarse_voxel_mm = 0; }, "PlanRequest.coarse_voxel_mm");
  // The rest as the loop's own options name them.
  testing::expect_option_refused(
      PlanRequest{}, [](auto& o) { o.scout_nside = 0; }, "PlanningOptions.scout_nside");
  testing::expect_option_refused(
      PlanRequest{}, [](auto& o) { o.spread_exponent = 0; }, "PlannerOptions.spread_exponent");
  testing::expect_option_refused(
      PlanRequest{}, [](auto& o) { o.binning = 0; }, "IncrementalOptions.binning");
  testing::expect_option_refused(
      PlanRequest{}, [](auto& o) { o.tangent_width_deg = 0; }, "EdgeTangencyOptions.tangent_width_deg");

  LabPlanRequest lab;
  lab.lab = "lab";
  lab.setup = "lab-scan.json";
  lab.out = "planned";
  EXPECT_NO_THROW(lab.validate());
  testing::expect_option_refused(
      lab, [](auto& o) { o.lab.clear(); }, "LabPlanRequest.lab");
  testing::expect_option_refused(
      lab, [](auto& o) { o.setup.clear(); }, "LabPlanRequest.setup");
  testing::expect_option_refused(
      lab, [](auto& o) { o.out.clear(); }, "LabPlanRequest.out");
  testing::expect_option_refused(
      lab, [](auto& o) { o.sod_mm = 0; }, "LabPlanRequest.sod_mm");
  testing::expect_option_refused(
      lab, [](auto& o) { o.timeout_s = 0; }, "LabPlanRequest.timeout_s");
  testing::expect_option_refused(
      lab, [](auto& o) { o.plan.views = 0; }, "PlanRequest.views");

  SimulatedPlanRequest simulated;
  simulated.phantoms = {"sample-1"};
  EXPECT_NO_THROW(simulated.validate());
  testing::expect_option_refused(
      simulated, [](auto& o) { o.phantoms.clear(); }, "SimulatedPlanRequest.phantoms");
  testing::expect_option_refused(
      simulated, [](auto& o) { o.cols = 8; }, "SimulatedPlanRequest.cols");
  testing::expect_option_refused(
      simulated, [](auto& o) { o.pitch_mm = -1; }, "SimulatedPlanRequest.pitch_mm");
  testing::expect_option_refused(
      simulated, [](auto& o) { o.sdd_mm = 1000; }, "SimulatedPlanRequest.sdd_mm");
  testing::expect_option_refused(
      simulated, [](auto& o) { o.kvp = 200; }, "SimulatedPlanRequest.kvp");
  testing::expect_option_refused(
      simulated, [](auto& o) { o.flat_counts = 0; }, "SimulatedPlanRequest.flat_counts");
  testing::expect_option_refused(
      simulated, [](auto& o) { o.random_draws = 0; }, "SimulatedPlanRequest.random_draws");
  testing::expect_option_refused(
      simulated, [](auto& o) { o.comparison.voxel_mm = 0; }, "ComparisonOptions.voxel_mm");
  testing::expect_option_refused(
      simulated, [](auto& o) { o.comparison.iterations = 0; }, "ComparisonOptions.iterations");
  testing::expect_option_refused(
      simulated, [](auto& o) { o.comparison.size = -1; }, "ComparisonOptions.size");
  testing::expect_option_refused(
      simulated, [](auto& o) { o.comparison.lambda = -1; }, "ComparisonOptions.lambda");
  testing::expect_option_refused(
      simulated, [](auto& o) { o.comparison.binning = 0; }, "ComparisonOptions.binning");
}

}  // namespace
}  // namespace ctk

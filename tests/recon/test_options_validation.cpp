// The options structs of libproj and librecon check themselves: the defaults pass; each field out
// of its range is refused, naming the struct and the field, before any work.
#include <gtest/gtest.h>

#include <limits>
#include <string>

#include "../test_support.hpp"
#include "ctk/measure/measurements.hpp"
#include "ctk/proj/joseph_operator.hpp"
#include "ctk/recon/markerless_refinement.hpp"
#include "ctk/recon/os_sqs.hpp"
#include "ctk/recon/reconstruction_run.hpp"
#include "ctk/recon/refine_scan.hpp"
#include "ctk/recon/sirt.hpp"
#include "ctk/recon/wls_cg.hpp"

namespace ctk {
namespace {

TEST(OptionsValidation, RefineScanOptions) {
  EXPECT_NO_THROW(RefineScanOptions{}.validate());
  testing::expect_option_refused(
      RefineScanOptions{}, [](auto& o) { o.coarsening = 0.5; }, "RefineScanOptions.coarsening");
  testing::expect_option_refused(
      RefineScanOptions{}, [](auto& o) { o.blur_arc_deg = -1; }, "RefineScanOptions.blur_arc_deg");
  testing::expect_option_refused(
      RefineScanOptions{}, [](auto& o) { o.z_accept = std::numeric_limits<double>::infinity(); }, "RefineScanOptions.z_accept");
  // The workflow checks before it reads a file: this scan names no images at all.
  RefineScanOptions bad;
  bad.z_accept = 0;
  EXPECT_THROW(refine_scan(ScanDescription{}, Geometry{}, bad), std::invalid_argument);
}

TEST(OptionsValidation, ReconstructionOptions) {
  EXPECT_NO_THROW(ReconstructionOptions{}.validate());
  testing::expect_option_refused(
      ReconstructionOptions{}, [](auto& o) { o.iterations = -1; }, "ReconstructionOptions.iterations");
  testing::expect_option_refused(
      ReconstructionOptions{}, [](auto& o) { o.subsets = -2; }, "ReconstructionOptions.subsets");
  testing::expect_option_refused(
      ReconstructionOptions{}, [](auto& o) { o.lambda = -1; }, "ReconstructionOptions.lambda");
  testing::expect_option_refused(
      ReconstructionOptions{}, [](auto& o) { o.tolerance = 1; }, "ReconstructionOptions.tolerance");
  testing::expect_option_refused(
      ReconstructionOptions{},
      [](auto& o) {
        o.size = {64, -1, 64};
      },
      "ReconstructionOptions.size");
  testing::expect_option_refused(
      ReconstructionOptions{}, [](auto& o) { o.voxel_mm = -0.5; }, "ReconstructionOptions.voxel_mm");
  // A Huber penalty only with the method that minimises it.
  testing::expect_option_refused(
      ReconstructionOptions{},
      [](auto& o) {
        o.method = ReconstructionMethod::wls_cg;
        o.huber_delta = 0.001;
      },
      "ReconstructionOptions.huber_delta");
  testing::expect_option_refused(
      ReconstructionOptions{}, [](auto& o) { o.held_out_every = -1; }, "ReconstructionOptions.held_out_every");
  ReconstructionOptions huber;
  huber.method = ReconstructionMethod::os_sqs;
  huber.huber_delta = 0.001;
  EXPECT_NO_THROW(huber.validate());
  // The diagonal preconditioner only with the method it preconditions.
  testing::expect_option_refused(
      huber, [](auto& o) { o.preconditioner = CgPreconditioner::diagonal; }, "ReconstructionOptions.preconditioner");
  ReconstructionOptions preconditioned;
  preconditioned.method = ReconstructionMethod::wls_cg;
  preconditioned.preconditioner = CgPreconditioner::diagonal;
  EXPECT_NO_THROW(preconditioned.validate());
  EXPECT_THROW(cg_preconditioner_from_string("jacobi"), std::invalid_argument);
  EXPECT_EQ(cg_preconditioner_from_string("diagonal"), CgPreconditioner::diagonal);
  EXPECT_THROW(reconstruction_method("art"), std::invalid_argument);
  EXPECT_EQ(reconstruction_method("os-sqs"), ReconstructionMethod::os_sqs);
}

TEST(OptionsValidation, MeasurementOptions) {
  EXPECT_NO_THROW(MeasurementOptions{}.validate());
  testing::expect_option_refused(
      MeasurementOptions{}, [](auto& o) { o.shares = 0; }, "MeasurementOptions.shares");
  testing::expect_option_refused(
      MeasurementOptions{}, [](auto& o) { o.share = 1; }, "MeasurementOptions.share");  // of 1 share
  // The reader checks before it reads a file.
  MeasurementOptions bad;
  bad.share = -1;
  EXPECT_THROW(load_measurements(ScanDescription{}, Geometry{}, bad), std::invalid_argument);
}

TEST(OptionsValidation, OsSqsOptions) {
  EXPECT_NO_THROW(OsSqsOptions{}.validate());
  testing::expect_option_refused(
      OsSqsOptions{}, [](auto& o) { o.epochs = -1; }, "OsSqsOptions.epochs");
  testing::expect_option_refused(
      OsSqsOptions{}, [](auto& o) { o.lambda = std::numeric_limits<double>::quiet_NaN(); }, "OsSqsOptions.lambda");
  testing::expect_option_refused(
      OsSqsOptions{}, [](auto& o) { o.huber_delta = -0.001; }, "OsSqsOptions.huber_delta");
}

TEST(OptionsValidation, SirtOptions) {
  EXPECT_NO_THROW(SirtOptions{}.validate());
  testing::expect_option_refused(
      SirtOptions{}, [](auto& o) { o.relaxation = 2.0; }, "SirtOptions.relaxation");
  testing::expect_option_refused(
      SirtOptions{}, [](auto& o) { o.relaxation = 0.0; }, "SirtOptions.relaxation");
  testing::expect_option_refused(
      SirtOptions{}, [](auto& o) { o.iterations = -1; }, "SirtOptions.iterations");
  // The solver checks before any work.
  Volume x(VolumeLayout::centred({4, 4, 4}, Eigen::Vector3d::Ones()));
  EXPECT_THROW(solve_sirt(JosephOperator({}, x.layout, 4, 4), ProjectionStack(0, 4, 4), x, {10, 2.5, true}),
               std::invalid_argument);
}

TEST(OptionsValidation, WlsOptions) {
  EXPECT_NO_THROW(WlsOptions{}.validate());
  testing::expect_option_refused(
      WlsOptions{}, [](auto& o) { o.iterations = -3; }, "WlsOptions.iterations");
  testing::expect_option_refused(
      WlsOptions{}, [](auto& o) { o.tolerance = -1e-4; }, "WlsOptions.tolerance");
  testing::expect_option_refused(
      WlsOptions{}, [](auto& o) { o.tolerance = 1.0; }, "WlsOptions.tolerance");
  testing::expect_option_refused(
      WlsOptions{}, [](auto& o) { o.lambda = -0.5; }, "WlsOptions.lambda");
  testing::expect_option_refused(
      WlsOptions{}, [](auto& o) { o.lambda = std::numeric_limits<double>::infinity(); }, "WlsOptions.lambda");
}

TEST(OptionsValidation, ProjectorOptions) {
  EXPECT_NO_THROW(ProjectorOptions{}.validate());
  testing::expect_option_refused(
      ProjectorOptions{}, [](auto& o) { o.threads = -2; }, "ProjectorOptions.threads");
  testing::expect_option_refused(
      ProjectorOptions{}, [](auto& o) { o.rows_per_block = -1; }, "ProjectorOptions.rows_per_block");
  EXPECT_THROW(JosephProjector(ProjectorOptions{0, -8}), std::invalid_argument);
}

TEST(OptionsValidation, RefinementOptions) {
  EXPECT_NO_THROW(RefinementOptions{}.validate());
  testing::expect_option_refused(
      RefinementOptions{}, [](auto& o) { o.z_accept = 0; }, "RefinementOptions.z_accept");
  testing::expect_option_refused(
      RefinementOptions{}, [](auto& o) { o.max_rounds = 0; }, "RefinementOptions.max_rounds");
  testing::expect_option_refused(
      RefinementOptions{}, [](auto& o) { o.sharpness_tolerance = 1.5; }, "RefinementOptions.sharpness_tolerance");
  testing::expect_option_refused(
      RefinementOptions{}, [](auto& o) { o.nominal_blur_arc_deg = -1; }, "RefinementOptions.nominal_blur_arc_deg");
}

}  // namespace
}  // namespace ctk

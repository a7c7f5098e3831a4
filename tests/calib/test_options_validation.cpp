// libcalib's options structs check themselves: the defaults pass; each field out of its range is
// refused, naming the struct and the field, before any work.
#include <gtest/gtest.h>

#include <string>

#include "../test_support.hpp"
#include "ctk/calib/calibration_run.hpp"
#include "ctk/calib/diagnosis.hpp"
#include "ctk/calib/diagnosis_run.hpp"
#include "ctk/calib/robot_prior.hpp"
#include "ctk/calib/sphere_detection.hpp"
#include "ctk/calib/sphere_profile_fit.hpp"
#include "ctk/calib/view_calibration.hpp"

namespace ctk {
namespace {

TEST(OptionsValidation, CalibrationOptions) {
  EXPECT_NO_THROW(CalibrationOptions{}.validate());
  testing::expect_option_refused(
      CalibrationOptions{}, [](auto& o) { o.min_spheres = 5; }, "CalibrationOptions.min_spheres");
  testing::expect_option_refused(
      CalibrationOptions{}, [](auto& o) { o.max_rms_px = 0; }, "CalibrationOptions.max_rms_px");
  testing::expect_option_refused(
      CalibrationOptions{}, [](auto& o) { o.search_px = -40; }, "CalibrationOptions.search_px");
  testing::expect_option_refused(
      CalibrationOptions{}, [](auto& o) { o.robust_px = 0; }, "CalibrationOptions.robust_px");
  testing::expect_option_refused(
      CalibrationOptions{}, [](auto& o) { o.max_first_guess_error_deg = 200; }, "CalibrationOptions.max_first_guess_error_deg");
}

TEST(OptionsValidation, CalibrationRunOptions) {
  EXPECT_NO_THROW(CalibrationRunOptions{}.validate());
  testing::expect_option_refused(
      CalibrationRunOptions{}, [](auto& o) { o.calibration.min_spheres = 5; }, "CalibrationOptions.min_spheres");
  // The workflow checks before it reads a file: this scan names no images at all.
  CalibrationRunOptions bad;
  bad.calibration.robust_px = 0;
  EXPECT_THROW(run_calibration(ScanDescription{}, bad), std::invalid_argument);
}

TEST(OptionsValidation, DiagnosisRunOptions) {
  EXPECT_NO_THROW(DiagnosisRunOptions{}.validate());
  DiagnosisRunOptions stated;
  stated.repeatability_mm = 0.05;
  stated.repeatability_deg = 0.01;
  EXPECT_NO_THROW(stated.validate());
  testing::expect_option_refused(
      DiagnosisRunOptions{}, [](auto& o) { o.repeatability_mm = 0.0; }, "DiagnosisRunOptions.repeatability_mm");
  testing::expect_option_refused(
      DiagnosisRunOptions{}, [](auto& o) { o.repeatability_deg = -0.01; }, "DiagnosisRunOptions.repeatability_deg");
  testing::expect_option_refused(
      DiagnosisRunOptions{}, [](auto& o) { o.calibration.max_rms_px = 0; }, "CalibrationOptions.max_rms_px");
  testing::expect_option_refused(
      DiagnosisRunOptions{}, [](auto& o) { o.diagnosis.best_lead_z = -1; }, "DiagnosisOptions.best_lead_z");
}

TEST(OptionsValidation, RobotPriorOptions) {
  EXPECT_NO_THROW(RobotPriorOptions{}.validate());
  testing::expect_option_refused(
      RobotPriorOptions{}, [](auto& o) { o.min_views = 11; }, "RobotPriorOptions.min_views");
  testing::expect_option_refused(
      RobotPriorOptions{}, [](auto& o) { o.start_sigma_mm = 0; }, "RobotPriorOptions.start_sigma_mm");
  testing::expect_option_refused(
      RobotPriorOptions{}, [](auto& o) { o.start_sigma_deg = -0.02; }, "RobotPriorOptions.start_sigma_deg");
}

TEST(OptionsValidation, DetectionOptions) {
  EXPECT_NO_THROW(DetectionOptions{}.validate());
  testing::expect_option_refused(
      DetectionOptions{}, [](auto& o) { o.radius_px = 0; }, "DetectionOptions.radius_px");
  testing::expect_option_refused(
      DetectionOptions{}, [](auto& o) { o.noise_sigmas = -1; }, "DetectionOptions.noise_sigmas");
  testing::expect_option_refused(
      DetectionOptions{}, [](auto& o) { o.min_roundness = 1.5; }, "DetectionOptions.min_roundness");
  testing::expect_option_refused(
      DetectionOptions{}, [](auto& o) { o.max_candidates = 0; }, "DetectionOptions.max_candidates");
  // The detector checks before any work.
  DetectionOptions bad;
  bad.radius_px = -2;
  EXPECT_THROW(detect_spheres(Image{8, 8, std::vector<float>(64, 0.0f)}, bad), std::invalid_argument);
}

TEST(OptionsValidation, ProfileFitOptions) {
  EXPECT_NO_THROW(ProfileFitOptions{}.validate());
  testing::expect_option_refused(
      ProfileFitOptions{}, [](auto& o) { o.margin_px = 0; }, "ProfileFitOptions.margin_px");
  testing::expect_option_refused(
      ProfileFitOptions{}, [](auto& o) { o.subsamples = 0; }, "ProfileFitOptions.subsamples");
  testing::expect_option_refused(
      ProfileFitOptions{}, [](auto& o) { o.max_move_px = -1; }, "ProfileFitOptions.max_move_px");
}

TEST(OptionsValidation, DiagnosisOptions) {
  EXPECT_NO_THROW(DiagnosisOptions{}.validate());
  testing::expect_option_refused(
      DiagnosisOptions{}, [](auto& o) { o.z_accept = 0; }, "DiagnosisOptions.z_accept");
  testing::expect_option_refused(
      DiagnosisOptions{}, [](auto& o) { o.robot_sigma_mm = 0; }, "DiagnosisOptions.robot_sigma_mm");
  testing::expect_option_refused(
      DiagnosisOptions{}, [](auto& o) { o.robot_sigma_deg = -0.01; }, "DiagnosisOptions.robot_sigma_deg");
  testing::expect_option_refused(
      DiagnosisOptions{}, [](auto& o) { o.max_effects = 0; }, "DiagnosisOptions.max_effects");
  testing::expect_option_refused(
      DiagnosisOptions{}, [](auto& o) { o.min_image_effect_px = -0.01; }, "DiagnosisOptions.min_image_effect_px");
  testing::expect_option_refused(
      DiagnosisOptions{}, [](auto& o) { o.best_lead_z = -1; }, "DiagnosisOptions.best_lead_z");
  // The diagnosis checks before any work.
  DiagnosisOptions bad;
  bad.max_effects = 0;
  EXPECT_THROW(diagnose(ScanObservations{}, bad), std::invalid_argument);
}

}  // namespace
}  // namespace ctk

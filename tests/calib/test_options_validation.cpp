// libcalib's options structs check themselves: the defaults pass; each field out of its range is
// refused, naming the struct and the field, before any work.
#include <gtest/gtest.h>

#include <string>

#include "../test_support.hpp"
#include "ctk/calib/robot_prior.hpp"
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

TEST(OptionsValidation, RobotPriorOptions) {
  EXPECT_NO_THROW(RobotPriorOptions{}.validate());
  testing::expect_option_refused(
      RobotPriorOptions{}, [](auto& o) { o.min_views = 11; }, "RobotPriorOptions.min_views");
  testing::expect_option_refused(
      RobotPriorOptions{}, [](auto& o) { o.start_sigma_mm = 0; }, "RobotPriorOptions.start_sigma_mm");
  testing::expect_option_refused(
      RobotPriorOptions{}, [](auto& o) { o.start_sigma_deg = -0.02; }, "RobotPriorOptions.start_sigma_deg");
}

}  // namespace
}  // namespace ctk

// A helix fitted to sphere centres: the drawing's parameters recovered from centres on a tilted,
// shifted helix, and each centre's deviation from the curve where it was put.
#include <gtest/gtest.h>

#include <cmath>

#include "ctk/calib/helix_fit.hpp"
#include "ctk/calib/view_calibration.hpp"
#include "ctk/geom/holder_file.hpp"

namespace ctk {
namespace {

TEST(HelixFit, RecoversATiltedShiftedHelixAndEachCentresDeviation) {
  const Holder declared = thesis_first_holder();
  HelixFit truth;
  truth.helix = {19.62, declared.helix.rho_rad_per_mm * 1.004, 0.03};
  truth.axis_tilt_rad = {0.004, -0.0025};
  truth.axis_offset_mm = {0.08, -0.05};
  std::vector<Eigen::Vector3d> centres;
  for (std::size_t k = 0; k < declared.spheres_mm.size(); ++k) {
    const double tau = -24.0 + 48.0 * static_cast<double>(k) / 49.0;
    // Every fifth sphere 0.1 mm off the curve across it, outwards and inwards in turn (where no
    // helix absorbs it, and leaving the radius alone).
    const double angle = truth.helix.rho_rad_per_mm * tau + truth.helix.phase_rad;
    const Eigen::Vector3d outwards(std::cos(angle), std::sin(angle), 0.0);
    centres.push_back(truth.at(tau) + (k % 10 == 0 ? 0.1 : k % 10 == 5 ? -0.1 : 0.0) * outwards);
  }
  const HelixFit fit = fit_helix(centres, declared.helix);
  ASSERT_TRUE(fit.converged);
  EXPECT_NEAR(fit.helix.radius_mm, truth.helix.radius_mm, 0.01);
  EXPECT_NEAR(fit.helix.rho_rad_per_mm, truth.helix.rho_rad_per_mm, 1e-4);
  EXPECT_NEAR(fit.axis_tilt_rad.x(), truth.axis_tilt_rad.x(), 5e-4);
  EXPECT_NEAR(fit.axis_tilt_rad.y(), truth.axis_tilt_rad.y(), 5e-4);
  EXPECT_NEAR(fit.axis_offset_mm.x(), truth.axis_offset_mm.x(), 0.01);
  EXPECT_NEAR(fit.axis_offset_mm.y(), truth.axis_offset_mm.y(), 0.01);
  for (std::size_t k = 0; k < centres.size(); ++k) {
    if (k % 5 == 0)
      EXPECT_NEAR(fit.deviation_mm[k].norm(), 0.1, 0.015) << k;
    else
      EXPECT_LT(fit.deviation_mm[k].norm(), 0.015) << k;
  }
  // On the declared centres themselves the fit is the drawing, exactly.
  const HelixFit exact = fit_helix(declared.spheres_mm, declared.helix);
  EXPECT_LT(exact.rms_deviation_mm, 1e-9);
  EXPECT_THROW(fit_helix({declared.spheres_mm.begin(), declared.spheres_mm.begin() + 3}, declared.helix), std::invalid_argument);
}

// A view is rejected for its residual when it stands out: against the options' limit while the
// scan's views fit better, against twice the scan's median when every view fits worse.
TEST(ResidualLimit, FollowsTheScanWhenEveryViewIsHigh) {
  CalibrationOptions o;
  std::vector<ViewCalibration> views(20);
  for (std::size_t i = 0; i < views.size(); ++i) {
    views[i].residual_decides = true;
    views[i].rms_px = 0.1 + 0.005 * static_cast<double>(i);
  }
  EXPECT_DOUBLE_EQ(residual_limit_px(views, o), o.max_rms_px);
  for (auto& v : views) v.rms_px += 0.7;  // a printed holder: every view 0.8-0.9 px
  views[19].rms_px = 3.0;                 // and one view that is wrong
  const double limit = residual_limit_px(views, o);
  EXPECT_GT(limit, 1.5);
  EXPECT_LT(limit, 1.9);
  judge_residual(views[3], limit);
  judge_residual(views[19], limit);
  EXPECT_EQ(views[3].status, ViewStatus::ok);
  EXPECT_EQ(views[19].status, ViewStatus::rejected);
  EXPECT_NE(views[19].reason.find("residual above threshold"), std::string::npos);
}

}  // namespace
}  // namespace ctk

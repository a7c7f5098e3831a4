#pragma once
// The holder's wall measured from the images, for scans that do not declare it: a calibrated
// view knows where the holder's axis is, so every pixel's ray has a distance d to the axis and an
// angle theta to it, and a tube of radii r < R adds mu (2 sqrt(R^2 - d^2) - 2 sqrt(r^2 - d^2)) /
// sin(theta) to its line integral (the second term only inside r); a pixel averages the
// transmission of rays across its area. Fitted per view over the band of the spheres (pixels on
// a sphere's disc left out), the radii of several views give the estimate; their spread and the
// views' depth uncertainty (the scale of every length in them) give its uncertainty.
// The tube's ends come from the same views: beyond the spheres' band the wall's shadow stops where
// the tube does, and the view's fitted tube cut at w = e is matched to the pixels there (rays
// passing within the wall's radii, never through the bore, where a sample may be). Within about
// 5 deg of the axis the ends decide every ray's path through the wall.
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "ctk/calib/scan_calibration.hpp"
#include "ctk/geom/helix.hpp"
#include "ctk/geom/scan.hpp"

namespace ctk {

struct WallMeasurement {
  HolderWall wall;                                // ends_mm set when at least 3 views see both ends
  double inner_sigma_mm = 0, outer_sigma_mm = 0;  // the medians' standard errors and the views' scale
  int views = 0;                                  // views whose fit converged
  std::optional<Eigen::Vector2d> ends_sigma_mm;   // with the ends: lower, upper
  int end_views = 0;                              // views that saw both ends (the fewer of the two)
};

/// Up to `count` views spread over the scan whose first-guess pose sees the holder from the side
/// (axis at least 60 deg from the beam): the sample to calibrate and measure the wall in.
std::vector<int> wall_sample_views(const ScanDescription& scan, int count = 12);

/// Measures the wall in up to `max_views` calibrated views that see the holder from the side
/// (axis at least 60 deg from the beam); empty when fewer than 3 such views fit. A sample that
/// reaches the inside of the wall biases the inner radius.
std::optional<WallMeasurement> measure_holder_wall(const ScanDescription& scan, const ScanCalibration& calibration,
                                                   int max_views = 12);

/// Whether the scan leaves its holder's wall, or the wall's ends, to be measured.
bool wall_to_measure(const ScanDescription& scan);

/// The wall calibration models: the declared radii with the measured ends, or all measured.
HolderWall modelled_wall(const ScanDescription& scan, const WallMeasurement& measured);

/// One line saying what was declared and measured of the wall ("" when it was declared whole).
std::string wall_line(const std::optional<HolderWall>& declared, const std::optional<WallMeasurement>& measured);

/// {"inner_radius_mm", "outer_radius_mm", "inner_sigma_mm", "outer_sigma_mm", "views",
///  "ends": {"ends_mm", "ends_sigma_mm", "views"} or null}.
nlohmann::json to_json(const WallMeasurement& m);

}  // namespace ctk

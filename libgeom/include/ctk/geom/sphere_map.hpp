#pragma once
// An equal-area map of the sphere of view directions for coverage pictures (Lambert cylindrical
// equal-area on the unit sphere, through GeographicLib): equal areas on the sphere stay equal.
#include <Eigen/Core>

namespace ctk {

struct MapPoint {
  double x = 0;  // longitude-like, [-pi, pi]
  double y = 0;  // sin(latitude), [-1, 1]
};

/// Latitude is measured from the holder's u-v plane towards +w; longitude from +u towards +v.
MapPoint equal_area_map(const Eigen::Vector3d& direction);
Eigen::Vector3d from_equal_area_map(const MapPoint& point);
/// Area of the full map: 4 pi, equal to the sphere's.
double equal_area_map_total_area();

}  // namespace ctk

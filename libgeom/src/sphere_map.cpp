#include "ctk/geom/sphere_map.hpp"

#include <GeographicLib/AlbersEqualArea.hpp>
#include <algorithm>
#include <cmath>

namespace ctk {

namespace {
// Unit sphere (a = 1, f = 0), standard parallel 0: Lambert's cylindrical equal-area projection.
const GeographicLib::AlbersEqualArea& projection() {
  static const GeographicLib::AlbersEqualArea p(1.0, 0.0, 0.0, 1.0);
  return p;
}
constexpr double kDeg = 180.0 / M_PI;
}  // namespace

MapPoint equal_area_map(const Eigen::Vector3d& direction) {
  const Eigen::Vector3d d = direction.normalized();
  const double lat = std::asin(std::clamp(d.z(), -1.0, 1.0)) * kDeg;
  const double lon = std::atan2(d.y(), d.x()) * kDeg;
  MapPoint p;
  projection().Forward(0.0, lat, lon, p.x, p.y);
  return p;
}

Eigen::Vector3d from_equal_area_map(const MapPoint& point) {
  double lat = 0, lon = 0;
  projection().Reverse(0.0, point.x, point.y, lat, lon);
  lat /= kDeg;
  lon /= kDeg;
  return {std::cos(lat) * std::cos(lon), std::cos(lat) * std::sin(lon), std::sin(lat)};
}

double equal_area_map_total_area() { return 2 * M_PI * 2.0; }

}  // namespace ctk

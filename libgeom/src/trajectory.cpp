#include "ctk/geom/trajectory.hpp"

#include <healpix_base.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <random>
#include <stdexcept>

namespace ctk {

std::vector<Eigen::Matrix3d> circular_rotations(const Eigen::Vector3d& axis, int count, double start_rad, double span_rad) {
  if (count <= 0) throw std::invalid_argument("circular_rotations: count must be positive");
  if (!(axis.norm() > 0)) throw std::invalid_argument("circular_rotations: axis must be non-zero");
  std::vector<Eigen::Matrix3d> out;
  out.reserve(static_cast<std::size_t>(count));
  for (int k = 0; k < count; ++k)
    out.push_back(Eigen::AngleAxisd(start_rad + span_rad * k / count, axis.normalized()).toRotationMatrix());
  return out;
}

Eigen::Matrix3d rotation_looking_along(const Eigen::Vector3d& direction) {
  const Eigen::Vector3d z = direction.normalized();
  Eigen::Vector3d up = Eigen::Vector3d::UnitZ() - z.z() * z;        // holder axis, perpendicular to the beam
  if (up.norm() < 1e-6) up = Eigen::Vector3d::UnitX() - z.x() * z;  // looking along the axis
  const Eigen::Vector3d y = -up.normalized();                       // camera +y is image "down"
  const Eigen::Vector3d x = y.cross(z);
  Eigen::Matrix3d R;
  R.row(0) = x.transpose();
  R.row(1) = y.transpose();
  R.row(2) = z.transpose();
  return R;
}

namespace {
Healpix_Base base(int nside) { return Healpix_Base(nside, RING, SET_NSIDE); }
}  // namespace

HealpixSphere::HealpixSphere(int nside) : nside_(nside) {
  if (nside <= 0 || nside > (1 << 13)) throw std::invalid_argument("HealpixSphere: Nside must be in 1..8192");
}

int HealpixSphere::size() const { return 12 * nside_ * nside_; }

Eigen::Vector3d HealpixSphere::direction(int cell) const {
  const vec3 v = base(nside_).pix2vec(cell);
  return {v.x, v.y, v.z};
}

int HealpixSphere::cell_of(const Eigen::Vector3d& d) const { return base(nside_).vec2pix(vec3(d.x(), d.y(), d.z())); }

std::vector<int> HealpixSphere::cells_within(const Eigen::Vector3d& d, double radius_rad) const {
  rangeset<int> cells;
  base(nside_).query_disc(pointing(vec3(d.x(), d.y(), d.z())), radius_rad, cells);
  std::vector<int> out;
  cells.toVector(out);
  return out;
}

double HealpixSphere::cell_area_sr() const { return 4 * M_PI / size(); }

std::vector<Eigen::Vector3d> HealpixSphere::directions() const {
  std::vector<Eigen::Vector3d> out;
  out.reserve(static_cast<std::size_t>(size()));
  for (int i = 0; i < size(); ++i) out.push_back(direction(i));
  return out;
}

std::vector<Eigen::Vector3d> random_directions(int count, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> normal(0.0, 1.0);
  std::vector<Eigen::Vector3d> out;
  while (static_cast<int>(out.size()) < count) {
    const Eigen::Vector3d v(normal(rng), normal(rng), normal(rng));
    if (v.norm() > 1e-9) out.push_back(v.normalized());
  }
  return out;
}

std::vector<Eigen::Vector3d> spinning_cap_directions(int count, double min_polar_rad, double max_polar_rad) {
  if (count <= 0) throw std::invalid_argument("spinning_cap_directions: count must be positive");
  if (!(0 <= min_polar_rad && min_polar_rad <= max_polar_rad && max_polar_rad <= M_PI))
    throw std::invalid_argument("spinning_cap_directions: polar angles must satisfy 0 <= min <= max <= pi");
  const double golden_angle = M_PI * (3.0 - std::sqrt(5.0));
  const double c0 = std::cos(min_polar_rad), c1 = std::cos(max_polar_rad);
  std::vector<Eigen::Vector3d> out;
  out.reserve(static_cast<std::size_t>(count));
  for (int k = 0; k < count; ++k) {
    // Cell centres of equal-area bands, from the axis outwards.
    const double c = c0 + (c1 - c0) * (k + 0.5) / count;
    const double s = std::sqrt(std::max(0.0, 1 - c * c)), phi = golden_angle * k;
    out.emplace_back(s * std::cos(phi), s * std::sin(phi), c);
  }
  return out;
}

double angular_distance_rad(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  // atan2 of |a x b| and a.b: accurate for small and large angles alike.
  return std::atan2(a.cross(b).norm(), a.dot(b));
}

double line_distance_rad(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  return std::atan2(a.cross(b).norm(), std::abs(a.dot(b)));
}

std::vector<int> neighbours_within(const std::vector<Eigen::Vector3d>& directions, int i, double radius_rad) {
  std::vector<int> out;
  const auto& d = directions.at(static_cast<std::size_t>(i));
  for (std::size_t j = 0; j < directions.size(); ++j)
    if (static_cast<int>(j) != i && angular_distance_rad(d, directions[j]) <= radius_rad) out.push_back(static_cast<int>(j));
  return out;
}

}  // namespace ctk

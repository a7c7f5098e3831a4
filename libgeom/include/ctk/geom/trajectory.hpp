#pragma once
// View sets: orientations of the holder relative to the beam. A view direction d is the beam
// direction seen in the holder frame; the holder rotation R_camera_holder takes d to +z.
#include <Eigen/Core>
#include <cstdint>
#include <vector>

namespace ctk {

/// `count` rotations about `axis` (any unit vector, holder frame), equally spaced from `start_rad`
/// over `span_rad` (2 pi: a full orbit without repeating the first view).
std::vector<Eigen::Matrix3d> circular_rotations(const Eigen::Vector3d& axis, int count, double start_rad, double span_rad);

/// The holder rotation that looks along `direction` (holder frame): R * direction = +z. The roll
/// about the beam puts the holder axis +w as close to image "up" (-v, camera -y) as it can go.
Eigen::Matrix3d rotation_looking_along(const Eigen::Vector3d& direction);

/// HEALPix pixelisation of the sphere of view directions (RING order): 12 Nside^2 equal-area cells.
class HealpixSphere {
 public:
  explicit HealpixSphere(int nside);
  int nside() const { return nside_; }
  int size() const;
  Eigen::Vector3d direction(int cell) const;  // unit vector of the cell centre
  int cell_of(const Eigen::Vector3d& direction) const;
  std::vector<int> cells_within(const Eigen::Vector3d& direction, double radius_rad) const;
  double cell_area_sr() const;
  std::vector<Eigen::Vector3d> directions() const;

 private:
  int nside_;
};

/// `count` directions uniform on the sphere, reproducible from `seed`.
std::vector<Eigen::Vector3d> random_directions(int count, std::uint64_t seed);

/// `count` directions on the band of the sphere whose angle to the holder axis (+z) lies in
/// [min_polar_rad, max_polar_rad], equal areas per view (cosine of the polar angle in equal
/// steps) while the holder spins about its axis by the golden angle from one view to the next:
/// a cap of axis directions, down to views looking almost along the axis.
std::vector<Eigen::Vector3d> spinning_cap_directions(int count, double min_polar_rad, double max_polar_rad);

double angular_distance_rad(const Eigen::Vector3d& a, const Eigen::Vector3d& b);
/// The angle between the lines along `a` and `b` (0 to pi/2): opposite directions are one line.
double line_distance_rad(const Eigen::Vector3d& a, const Eigen::Vector3d& b);
/// Indices j != i with angular distance <= radius.
std::vector<int> neighbours_within(const std::vector<Eigen::Vector3d>& directions, int i, double radius_rad);

}  // namespace ctk

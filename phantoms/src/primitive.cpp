#include "ctk/phantoms/primitive.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

namespace ctk {

const char* to_string(Shape shape) {
  switch (shape) {
    case Shape::sphere:
      return "sphere";
    case Shape::ellipsoid:
      return "ellipsoid";
    case Shape::cylinder:
      return "cylinder";
    case Shape::box:
      return "box";
    case Shape::mesh:
      return "mesh";
  }
  return "?";
}

Primitive Primitive::sphere(const Eigen::Vector3d& centre, double radius, double mu, std::string label) {
  return {Shape::sphere,
          Eigen::Vector3d::Constant(radius),
          make_rigid(Eigen::Matrix3d::Identity(), centre),
          mu,
          std::move(label),
          {},
          nullptr,
          {},
          1.0};
}

Primitive Primitive::ellipsoid(const Eigen::Vector3d& centre, const Eigen::Vector3d& radii, const Eigen::Matrix3d& R, double mu,
                               std::string label) {
  return {Shape::ellipsoid, radii, make_rigid(R, centre), mu, std::move(label), {}, nullptr, {}, 1.0};
}

Primitive Primitive::cylinder(const Eigen::Vector3d& centre, double radius, double height, const Eigen::Matrix3d& R, double mu,
                              std::string label) {
  return {Shape::cylinder,
          Eigen::Vector3d(radius, radius, 0.5 * height),
          make_rigid(R, centre),
          mu,
          std::move(label),
          {},
          nullptr,
          {},
          1.0};
}

Primitive Primitive::box(const Eigen::Vector3d& centre, const Eigen::Vector3d& size, const Eigen::Matrix3d& R, double mu,
                         std::string label) {
  return {Shape::box, 0.5 * size, make_rigid(R, centre), mu, std::move(label), {}, nullptr, {}, 1.0};
}

Primitive Primitive::from_mesh(std::shared_ptr<const TriangleMesh> mesh, const Eigen::Vector3d& origin, const Eigen::Matrix3d& R,
                               double mu, std::string label) {
  Primitive p;
  p.shape = Shape::mesh;
  p.half_size_mm = 0.5 * mesh->bounds().sizes();
  p.pose = make_rigid(R, origin);
  p.attenuation_per_mm = mu;
  p.label = std::move(label);
  p.mesh = std::move(mesh);
  return p;
}

namespace {

// Interval [t0, t1] of a line p + t d inside the slab |p_i + t d_i| <= 1; false when empty.
bool clip_to_slab(double p, double d, double& t0, double& t1) {
  if (d == 0) return std::abs(p) <= 1;
  double a = (-1 - p) / d, b = (1 - p) / d;
  if (a > b) std::swap(a, b);
  t0 = std::max(t0, a);
  t1 = std::min(t1, b);
  return t0 < t1;
}

// Interval of p + t d inside |x|^2 <= 1 over the first `n` coordinates (a unit ball or disc).
bool clip_to_unit_ball(const Eigen::Vector3d& p, const Eigen::Vector3d& d, int n, double& t0, double& t1) {
  const double a = d.head(n).squaredNorm(), b = p.head(n).dot(d.head(n)), c = p.head(n).squaredNorm() - 1;
  if (a == 0) return c <= 0;
  const double disc = b * b - a * c;
  if (disc <= 0) return false;
  // Numerically stable roots (no cancellation between b and sqrt(disc)).
  const double q = -(b + std::copysign(std::sqrt(disc), b));
  double r0 = q / a, r1 = q != 0 ? c / q : -r0;
  if (r0 > r1) std::swap(r0, r1);
  t0 = std::max(t0, r0);
  t1 = std::min(t1, r1);
  return t0 < t1;
}

}  // namespace

double Primitive::chord_mm(const Eigen::Vector3d& origin, const Eigen::Vector3d& direction) const {
  if (shape == Shape::mesh)
    return mesh->chord_mm(pose.linear().transpose() * (origin - pose.translation()), pose.linear().transpose() * direction);
  // Map the ray into the unit shape's coordinates; the ray parameter t (mm along the unit
  // direction) is unchanged by the affine map, so the chord is t1 - t0.
  const Eigen::Matrix3d& R = pose.linear();
  const Eigen::Vector3d p = (R.transpose() * (origin - pose.translation())).cwiseQuotient(half_size_mm);
  const Eigen::Vector3d d = (R.transpose() * direction).cwiseQuotient(half_size_mm);
  double t0 = 0, t1 = std::numeric_limits<double>::infinity();
  bool hit = false;
  switch (shape) {
    case Shape::sphere:
    case Shape::ellipsoid:
      hit = clip_to_unit_ball(p, d, 3, t0, t1);
      break;
    case Shape::cylinder:
      hit = clip_to_slab(p.z(), d.z(), t0, t1) && clip_to_unit_ball(p, d, 2, t0, t1);
      break;
    case Shape::box:
      hit = clip_to_slab(p.x(), d.x(), t0, t1) && clip_to_slab(p.y(), d.y(), t0, t1) && clip_to_slab(p.z(), d.z(), t0, t1);
      break;
    case Shape::mesh:
      break;  // above
  }
  return hit ? t1 - t0 : 0.0;
}

bool Primitive::contains(const Eigen::Vector3d& point) const {
  if (shape == Shape::mesh) return mesh->contains(pose.linear().transpose() * (point - pose.translation()));
  const Eigen::Vector3d p = (pose.linear().transpose() * (point - pose.translation())).cwiseQuotient(half_size_mm);
  switch (shape) {
    case Shape::sphere:
    case Shape::ellipsoid:
      return p.squaredNorm() <= 1;
    case Shape::cylinder:
      return p.head<2>().squaredNorm() <= 1 && std::abs(p.z()) <= 1;
    case Shape::box:
      return p.cwiseAbs().maxCoeff() <= 1;
    case Shape::mesh:
      break;  // above
  }
  return false;
}

std::array<Eigen::Vector3d, 8> Primitive::bounding_corners() const {
  std::array<Eigen::Vector3d, 8> corners;
  for (int i = 0; i < 8; ++i) {
    const Eigen::Vector3d sign(i & 1 ? 1 : -1, i & 2 ? 1 : -1, i & 4 ? 1 : -1);
    const Eigen::Vector3d centre = mesh ? Eigen::Vector3d(mesh->bounds().center()) : Eigen::Vector3d::Zero();
    corners[static_cast<std::size_t>(i)] = pose * (centre + sign.cwiseProduct(half_size_mm));
  }
  return corners;
}

}  // namespace ctk

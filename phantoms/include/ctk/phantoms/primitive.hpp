#pragma once
// Analytic primitives of a phantom: a sphere, ellipsoid, (elliptic) cylinder or box of uniform
// attenuation placed anywhere in the holder frame, or a closed triangle mesh (a lab's CAD part). Primitives add: a hole is a
// primitive of negative attenuation inside its material. Line integrals are exact chord lengths.
#include <Eigen/Core>
#include <array>
#include <memory>
#include <string>

#include "ctk/geom/rigid.hpp"
#include "ctk/phantoms/triangle_mesh.hpp"

namespace ctk {

enum class Shape { sphere, ellipsoid, cylinder, box, mesh };
const char* to_string(Shape shape);

struct Primitive {
  Shape shape = Shape::sphere;
  /// Semi-axes in the primitive's own frame (mm): radii for sphere/ellipsoid; radii x, y and half
  /// the height (along local z) for a cylinder; half the edge lengths for a box.
  Eigen::Vector3d half_size_mm{1, 1, 1};
  Rigid pose = Rigid::Identity();  // T_holder_primitive: centre and orientation
  double attenuation_per_mm = 0;   // linear attenuation coefficient, 1/mm (negative: a hole)
  std::string label;               // what it is ("sphere 12", "POM wall"), for files and reports
  /// What it is made of (material_attenuation.hpp), for polychromatic simulation: the attenuation
  /// above holds at the reference energy and scales like the material's. Empty: the same at every
  /// energy.
  std::string material;
  /// Shape::mesh: the solid in its own frame (the file's coordinates times its unit), placed by
  /// `pose`; `mesh_file` and `mesh_scale_mm` as the phantom file gives them.
  std::shared_ptr<const TriangleMesh> mesh;
  std::string mesh_file;
  double mesh_scale_mm = 1.0;

  static Primitive sphere(const Eigen::Vector3d& centre_mm, double radius_mm, double mu, std::string label = {});
  static Primitive ellipsoid(const Eigen::Vector3d& centre_mm, const Eigen::Vector3d& radii_mm, const Eigen::Matrix3d& rotation,
                             double mu, std::string label = {});
  /// Axis along the rotated local z.
  static Primitive cylinder(const Eigen::Vector3d& centre_mm, double radius_mm, double height_mm, const Eigen::Matrix3d& rotation,
                            double mu, std::string label = {});
  static Primitive box(const Eigen::Vector3d& centre_mm, const Eigen::Vector3d& size_mm, const Eigen::Matrix3d& rotation,
                       double mu, std::string label = {});
  /// The mesh's origin put at `origin_mm`, its axes turned by `rotation`.
  static Primitive from_mesh(std::shared_ptr<const TriangleMesh> mesh, const Eigen::Vector3d& origin_mm,
                             const Eigen::Matrix3d& rotation, double mu, std::string label = {});

  /// Length (mm) of the part of the ray origin + t * direction, t >= 0, inside the primitive.
  /// `direction` must be a unit vector.
  double chord_mm(const Eigen::Vector3d& origin, const Eigen::Vector3d& direction) const;
  /// Line integral of the attenuation along the ray: attenuation_per_mm * chord_mm.
  double line_integral(const Eigen::Vector3d& origin, const Eigen::Vector3d& direction) const {
    return attenuation_per_mm * chord_mm(origin, direction);
  }
  bool contains(const Eigen::Vector3d& point) const;
  /// Corners of a box enclosing the primitive (holder frame).
  std::array<Eigen::Vector3d, 8> bounding_corners() const;
};

}  // namespace ctk

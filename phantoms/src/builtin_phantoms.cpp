#include "ctk/phantoms/builtin_phantoms.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <memory>

#include "ctk/core/error.hpp"
#include "ctk/phantoms/material_attenuation.hpp"

namespace ctk {

namespace {

using Eigen::Matrix3d;
using Eigen::Vector3d;

constexpr double kDegree = M_PI / 180.0;
const Matrix3d kIdentity = Matrix3d::Identity();

Matrix3d about_u(double deg) { return rotation_about(Vector3d::UnitX(), deg * kDegree); }
Matrix3d about_v(double deg) { return rotation_about(Vector3d::UnitY(), deg * kDegree); }
Matrix3d about_w(double deg) { return rotation_about(Vector3d::UnitZ(), deg * kDegree); }

// A solid with a cylindrical hole: the hole is the same material with negative attenuation.
void add_hole(Phantom& p, const Vector3d& centre, double diameter, double length, const Matrix3d& R, double mu,
              const std::string& label) {
  p.primitives.push_back(Primitive::cylinder(centre, 0.5 * diameter, length, R, -mu, label));
}

// Names what every primitive added since `first` is made of (polychromatic simulation).
void made_of(Phantom& p, std::size_t first, const char* material) {
  for (std::size_t i = first; i < p.primitives.size(); ++i) p.primitives[i].material = material;
}

}  // namespace

Phantom helix_holder_phantom(const Holder& holder) {
  Phantom p{"helix-holder", {}};
  // A holder declared without its wall, or without the wall's ends, is simulated on the
  // reference holder's tube, or between its ends.
  const HolderWall reference = *reference_helix_holder().wall;
  const HolderWall wall = holder.wall.value_or(reference);
  const Eigen::Vector2d ends = wall.ends_mm.value_or(*reference.ends_mm);
  const Vector3d centre(0, 0, 0.5 * (ends.x() + ends.y()));
  const double height = ends.y() - ends.x();
  if (holder.body) {  // the lab's own body, as drawn
    const HolderBody& body = *holder.body;
    if (!is_known_material(body.material))
      throw InputError(body.mesh.string(), "material", "\"" + body.material + "\" is not a material the simulator knows");
    auto mesh = std::make_shared<const TriangleMesh>(TriangleMesh::read_stl(body.mesh, body.unit_mm));
    p.primitives.push_back(Primitive::from_mesh(std::move(mesh), Vector3d::Zero(), kIdentity,
                                                linear_attenuation_per_mm(body.material, kReferenceEnergyKeV), "holder body"));
    made_of(p, 0, body.material.c_str());
  } else {
    p.primitives.push_back(Primitive::cylinder(centre, wall.outer_radius_mm, height, kIdentity, material::pom, "POM tube"));
    p.primitives.push_back(Primitive::cylinder(centre, wall.inner_radius_mm, height, kIdentity, -material::pom, "POM tube bore"));
    made_of(p, 0, "pom");
  }
  const std::size_t spheres = p.primitives.size();
  for (std::size_t k = 0; k < holder.spheres_mm.size(); ++k)
    p.primitives.push_back(Primitive::sphere(holder.spheres_mm[k], 0.5 * holder.sphere_diameter_mm, material::aluminium,
                                             "sphere " + std::to_string(k)));
  made_of(p, spheres, "aluminium");
  return p;
}

Phantom shepp_logan_phantom(double s, double mu) {
  // Modified Shepp-Logan (Toft's higher-contrast densities), 3-D ellipsoid table on [-1, 1]^3:
  // density, semi-axes, centre, rotation about w (deg), then tilt about u (deg).
  struct Row {
    double density, a, b, c, x, y, z, phi, psi;
  };
  static const Row table[] = {
      {1.0, 0.6900, 0.920, 0.810, 0.00, 0.000, 0.00, 0, 0},     {-0.8, 0.6624, 0.874, 0.780, 0.00, -0.0184, 0.00, 0, 0},
      {-0.2, 0.1100, 0.310, 0.220, 0.22, 0.000, 0.00, -18, 10}, {-0.2, 0.1600, 0.410, 0.280, -0.22, 0.000, 0.00, 18, 10},
      {0.1, 0.2100, 0.250, 0.410, 0.00, 0.350, -0.15, 0, 0},    {0.1, 0.0460, 0.046, 0.050, 0.00, 0.100, 0.25, 0, 0},
      {0.1, 0.0460, 0.046, 0.050, 0.00, -0.100, 0.25, 0, 0},    {0.1, 0.0460, 0.023, 0.050, -0.08, -0.605, 0.00, 0, 0},
      {0.1, 0.0230, 0.023, 0.020, 0.00, -0.606, 0.00, 0, 0},    {0.1, 0.0230, 0.046, 0.020, 0.06, -0.605, 0.00, 0, 0},
  };
  Phantom p{"shepp-logan", {}};
  int k = 0;
  for (const Row& r : table)
    p.primitives.push_back(Primitive::ellipsoid(s * Vector3d(r.x, r.y, r.z), s * Vector3d(r.a, r.b, r.c),
                                                about_w(r.phi) * about_u(r.psi), mu * r.density,
                                                "ellipsoid " + std::to_string(k++)));
  made_of(p, 0, "water");
  return p;
}

Phantom brick_and_plate_phantom() {
  Phantom p{"brick-and-plate", {}};
  const double mu = material::abs_plastic;
  // A hollow toy brick (1.5 mm walls, open underneath) with four studs on top.
  const Vector3d brick_centre(-7, 0, 0), brick(31, 21, 31);
  p.primitives.push_back(Primitive::box(brick_centre, brick, kIdentity, mu, "brick"));
  p.primitives.push_back(
      Primitive::box(brick_centre - Vector3d(0, 0, 0.75), brick - Vector3d(3, 3, 1.5), kIdentity, -mu, "brick cavity"));
  for (int i = 0; i < 4; ++i) {
    const Vector3d stud = brick_centre + Vector3d(i % 2 ? 7.5 : -7.5, i / 2 ? 4.5 : -4.5, 0.5 * brick.z() + 0.9);
    p.primitives.push_back(Primitive::cylinder(stud, 2.4, 1.8, kIdentity, mu, "stud " + std::to_string(i)));
  }
  // The plate: 4 mm PVC, its long edges slanting 15 degrees out of the axis.
  p.primitives.push_back(Primitive::box(Vector3d(13, 0, 0), Vector3d(4, 26, 45), about_u(15), material::pvc, "plate"));
  made_of(p, 0, "abs");
  p.primitives.back().material = "pvc";  // the plate
  return p;
}

Phantom sample1_phantom() {
  Phantom p{"sample-1", {}};
  const double low = 0.015, high = 0.070;  // the thesis' 1.5 and 7.0, in units of 0.01/mm
  const Vector3d cube_centre(-6, 0, -12);
  p.primitives.push_back(Primitive::box(cube_centre, Vector3d(22, 18, 30), kIdentity, low, "cube"));
  add_hole(p, cube_centre, 7, 18, about_u(90), low, "cube hole");
  // The thesis' cylinder, 32 mm across, standing on the cube (it overhangs the cube's 22 x 18 mm
  // top) and 1 mm from the absorber; 22 mm from the holder's axis at most (the bore's radius is 25).
  const double radius = 16, height = 32;
  const Vector3d cylinder_centre(-6, 0, 3 + height / 2);
  p.primitives.push_back(Primitive::cylinder(cylinder_centre, radius, height, kIdentity, low, "cylinder"));
  // Across holes stop where their rim leaves the cylinder (a hole must stay inside its material).
  const double across = 2 * std::sqrt(radius * radius - 3.0 * 3.0);
  add_hole(p, cylinder_centre + Vector3d(0, 0, -7), 6, across, about_v(90), low, "cylinder hole 0");
  add_hole(p, cylinder_centre + Vector3d(0, 0, 7), 6, across, about_v(90), low, "cylinder hole 1");
  p.primitives.push_back(Primitive::box(Vector3d(13, 0, 0), Vector3d(4, 30, 50), kIdentity, high, "absorber"));
  made_of(p, 0, "abs");
  p.primitives.back().material = "aluminium";  // the absorber
  return p;
}

Phantom sample2_phantom() {
  Phantom p{"sample-2", {}};
  const double low = 0.015, high = 0.070;
  // Open box, 1.5 mm walls and floor, open at the top (+w).
  p.primitives.push_back(Primitive::box(Vector3d::Zero(), Vector3d(34, 34, 30), kIdentity, low, "box"));
  p.primitives.push_back(Primitive::box(Vector3d(0, 0, 0.75), Vector3d(31, 31, 28.5), kIdentity, -low, "box inside"));
  const double floor = -13.5;
  // A cube with a square hole (2 x 2 mm, through its 3 mm depth).
  const Vector3d cube(-7, -7, floor + 5);
  p.primitives.push_back(Primitive::box(cube, Vector3d(6, 3, 10), kIdentity, low, "small cube"));
  p.primitives.push_back(Primitive::box(cube, Vector3d(2, 3, 2), kIdentity, -low, "small cube hole"));
  const Vector3d cyl_a(7, -7, floor + 6);
  p.primitives.push_back(Primitive::cylinder(cyl_a, 3, 12, kIdentity, low, "cylinder"));
  add_hole(p, cyl_a, 2, 12, kIdentity, low, "cylinder hole");
  // The thesis' small cylinder: 3 mm across, 5 mm tall, a 0.8 mm hole along its axis.
  const Vector3d cyl_b(7, 7, floor + 2.5);
  p.primitives.push_back(Primitive::cylinder(cyl_b, 1.5, 5, kIdentity, low, "small cylinder"));
  add_hole(p, cyl_b, 0.8, 5, kIdentity, low, "small cylinder hole");
  // The plate at the box's centre, standing on its floor.
  p.primitives.push_back(Primitive::box(Vector3d(0, 0, floor + 6), Vector3d(1, 12, 12), kIdentity, high, "absorber"));
  made_of(p, 0, "abs");
  p.primitives.back().material = "aluminium";  // the absorber
  return p;
}

Phantom walnut_phantom() {
  Phantom p{"walnut", {}};
  const double shell = 0.030, kernel = 0.018;
  p.primitives.push_back(Primitive::ellipsoid(Vector3d::Zero(), Vector3d(15, 14, 18), kIdentity, shell, "shell"));
  p.primitives.push_back(Primitive::ellipsoid(Vector3d::Zero(), Vector3d(13.5, 12.5, 16.5), kIdentity, -shell, "shell cavity"));
  // Two kernel lobes either side of a thin septum, each folded: a stack of thin lens-shaped
  // slices turned against each other, separated by narrow gaps (attenuation only adds, so a fold
  // is made by leaving space, not by removing material).
  p.primitives.push_back(Primitive::ellipsoid(Vector3d::Zero(), Vector3d(0.4, 12.5, 16.5), kIdentity, shell, "septum"));
  for (int side = -1; side <= 1; side += 2)
    for (int slice = 0; slice < 6; ++slice) {
      const double w = -13.0 + 5.2 * slice;
      const double taper = std::sqrt(std::max(0.2, 1.0 - (w / 16.0) * (w / 16.0)));
      p.primitives.push_back(Primitive::ellipsoid(Vector3d(side * 6.5, 0, w), Vector3d(5.5 * taper, 11 * taper, 2.4),
                                                  about_w(side * 12.0 * (slice % 2 ? 1 : -1)), kernel,
                                                  "kernel fold " + std::to_string(slice)));
    }
  made_of(p, 0, "water");
  return p;
}

std::vector<std::string> builtin_phantom_names() {
  return {"helix-holder", "shepp-logan", "brick-and-plate", "sample-1", "sample-2", "walnut"};
}

Phantom builtin_phantom(const std::string& name) {
  if (name == "helix-holder") return helix_holder_phantom(reference_helix_holder());
  if (name == "shepp-logan") return shepp_logan_phantom();
  if (name == "brick-and-plate") return brick_and_plate_phantom();
  if (name == "sample-1") return sample1_phantom();
  if (name == "sample-2") return sample2_phantom();
  if (name == "walnut") return walnut_phantom();
  std::string names;
  for (const auto& n : builtin_phantom_names()) names += (names.empty() ? "" : ", ") + n;
  throw InputError(name, "", "not a built-in phantom (built in: " + names + "; a phantom file's name ends in .json)");
}

Phantom sample_of(const std::vector<std::string>& names_or_files, std::vector<std::string>* warnings) {
  Phantom sample;
  for (const std::string& name : names_or_files) {
    const Phantom p = std::filesystem::path(name).extension() == ".json" ? read_phantom(name, warnings) : builtin_phantom(name);
    if (!sample.name.empty()) sample.name += " + ";
    sample.name += p.name;
    sample.add(p);
  }
  return sample;
}

}  // namespace ctk

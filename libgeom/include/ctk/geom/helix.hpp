#pragma once
// The calibration holder: a helix of metal spheres in the holder frame H (scan-format.md):
// h(tau) = (r cos(rho tau + phi), r sin(rho tau + phi), tau).
#include <Eigen/Core>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "ctk/geom/projection_matrix.hpp"

namespace ctk {

struct Helix {
  double radius_mm = 0;
  double rho_rad_per_mm = 0;
  double phase_rad = 0;

  Eigen::Vector3d at(double tau) const;
  Eigen::Vector3d tangent(double tau) const;  // dh / dtau
  /// tau of the point of the helix nearest to p along the axis (p's w, refined on the curve).
  double nearest_tau(const Eigen::Vector3d& p) const;
};

/// The tube that carries the spheres, coaxial with the helix (the holder's w axis), between its
/// ends along the axis when they are known; otherwise treated as infinitely long. Seen from the
/// side the two agree wherever the ends lie beyond the rays, but within about 10 deg of the axis a
/// ray runs tens of millimetres inside the wall and the ends decide its path.
struct HolderWall {
  double inner_radius_mm = 0;
  double outer_radius_mm = 0;
  std::optional<Eigen::Vector2d> ends_mm;  // the tube's ends (w, holder frame), lower first

  /// Path length (mm) inside the wall along the line through `point` with direction `direction`.
  double chord_mm(const Eigen::Vector3d& point, const Eigen::Vector3d& direction) const;
};

/// The body a lab has drawn (its CAD mesh): what the simulator draws in place of the wall's tube.
/// Calibration still models the shadow of the wall the holder declares, if any.
struct HolderBody {
  std::filesystem::path mesh;  // STL, binary or ASCII, in the holder frame; absolute once read
  double unit_mm = 1.0;        // the file's length unit in mm
  std::string material = "pom";
};

struct Holder {
  Helix helix;
  double sphere_diameter_mm = 0;
  std::vector<Eigen::Vector3d> spheres_mm;  // declared centres, holder frame
  /// When declared, calibration models the wall's shadow under each sphere, so spheres seen on the
  /// wall's steep silhouette can be used too.
  std::optional<HolderWall> wall;
  std::optional<HolderBody> body;

  /// n spheres equally spaced in tau over [tau_begin, tau_end] — how a helix holder is designed.
  static Holder on_helix(const Helix& helix, double sphere_diameter_mm, int count, double tau_begin, double tau_end);
  double tau_min() const;  // extent of the spheres along the axis
  double tau_max() const;
};

/// The toolkit's reference holder: 50 spheres of 2 mm on a helix of radius 28 mm making two
/// turns over 80 mm (rho = 4 pi / 80 rad/mm), centred on the holder origin, on the outside of a
/// tube of inner radius 25 mm and outer radius 28 mm, 118 mm long and centred on it.
Holder reference_helix_holder();

struct HelixPoint {
  double tau = 0;
  Eigen::Vector2d uv;      // projection of h(tau)
  double distance_px = 0;  // from the query pixel
};

/// The point of the projected helix curve nearest to pixel `uv`, searched continuously over
/// tau in [tau_begin, tau_end] (a coarse scan for the basin, then Newton refinement).
HelixPoint closest_point_on_projected_helix(const ProjectionMatrix& P, const Helix& helix, const Eigen::Vector2d& uv,
                                            double tau_begin, double tau_end);

}  // namespace ctk

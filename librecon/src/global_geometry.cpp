#include "ctk/recon/global_geometry.hpp"

#include <Eigen/Geometry>
#include <cmath>

namespace ctk {

namespace {

// P' = P * (rotation by `angle` about `axis` through `centre`), in the frame P maps from.
ProjectionMatrix rotated_about(const ProjectionMatrix& P, const Eigen::Vector3d& axis, const Eigen::Vector3d& centre,
                               double angle) {
  const Eigen::Matrix3d R = Eigen::AngleAxisd(angle, axis.normalized()).toRotationMatrix();
  Eigen::Matrix4d T = Eigen::Matrix4d::Identity();
  T.topLeftCorner<3, 3>() = R;
  T.topRightCorner<3, 1>() = centre - R * centre;
  return ProjectionMatrix(Matrix34d(P.matrix() * T));
}

}  // namespace

std::vector<ProjectionMatrix> apply_global_geometry(const GlobalGeometry& g, const std::vector<ProjectionMatrix>& nominal,
                                                    const CircularTrajectory& orbit) {
  std::vector<ProjectionMatrix> out;
  out.reserve(nominal.size());
  for (const ProjectionMatrix& P0 : nominal) {
    ProjectionMatrix P = P0;
    if (g.tilt_rad != 0) {
      // The view's column direction in the volume frame: the axis that tilts the rotation axis
      // towards (or away from) the source.
      const Eigen::Vector3d towards_source = (P.source_position() - orbit.centre).normalized();
      const Eigen::Vector3d across = orbit.axis.cross(towards_source).normalized();
      P = rotated_about(P, across, orbit.centre, g.tilt_rad);
    }
    const auto K = P0.decompose().intrinsics;
    const Eigen::Vector2d pp(K.u0_px, K.v0_px);
    // Pixel map: move to the principal point, zoom, roll, move back shifted.
    Eigen::Matrix3d to_pp = Eigen::Matrix3d::Identity(), back = Eigen::Matrix3d::Identity(), rs = Eigen::Matrix3d::Identity();
    to_pp.topRightCorner<2, 1>() = -pp;
    back.topRightCorner<2, 1>() = pp + Eigen::Vector2d(g.du_px, g.dv_px);
    const double c = std::cos(g.roll_rad), s = std::sin(g.roll_rad);
    rs.topLeftCorner<2, 2>() << c, -s, s, c;
    rs.topLeftCorner<2, 2>() *= g.sdd_scale;
    out.emplace_back(Matrix34d(back * rs * to_pp * P.matrix()));
  }
  return out;
}

std::vector<ProjectionMatrix> angular_sub_views(const ProjectionMatrix& P, const CircularTrajectory& orbit, double arc_rad,
                                                int samples) {
  std::vector<ProjectionMatrix> out;
  for (int i = 0; i < samples; ++i) {
    const double offset = arc_rad * ((i + 0.5) / samples - 0.5);
    out.push_back(rotated_about(P, orbit.axis, orbit.centre, offset));
  }
  return out;
}

}  // namespace ctk

#include "ctk/geom/geometry_summary.hpp"

#include <cmath>
#include <iomanip>
#include <sstream>
#include <vector>

#include "ctk/core/statistics.hpp"

namespace ctk {

GeometrySummary summarize_geometry(const Geometry& g) {
  std::vector<double> sod, sdd, magnification, cone_u, cone_v, fov_u, fov_v, voxel;
  const Detector& d = g.detector;
  for (const GeometryView& v : g.views) {
    if (!v.P) continue;
    const ProjectionMatrix::Decomposition c = v.P->decompose();
    const double f_u = std::abs(c.intrinsics.fu_px), f_v = std::abs(c.intrinsics.fv_px);
    const double to_origin = v.P->source_position().norm();
    const double to_detector = f_u * d.pitch_u_mm;  // the detector plane's distance, in mm
    sod.push_back(to_origin);
    sdd.push_back(to_detector);
    magnification.push_back(to_detector / to_origin);
    cone_u.push_back(2 * std::atan(0.5 * d.cols / f_u) * 180 / M_PI);
    cone_v.push_back(2 * std::atan(0.5 * d.rows / f_v) * 180 / M_PI);
    fov_u.push_back(d.cols * d.pitch_u_mm * to_origin / to_detector);
    fov_v.push_back(d.rows * d.pitch_v_mm * to_origin / to_detector);
    voxel.push_back(d.pitch_u_mm * to_origin / to_detector);
  }
  GeometrySummary s;
  s.views = static_cast<int>(sod.size());
  if (s.views == 0) return s;
  s.source_to_origin_mm = median(sod);
  s.source_to_detector_mm = median(sdd);
  s.magnification = median(magnification);
  s.cone_angle_u_deg = median(cone_u);
  s.cone_angle_v_deg = median(cone_v);
  s.field_of_view_u_mm = median(fov_u);
  s.field_of_view_v_mm = median(fov_v);
  s.voxel_mm = median(voxel);
  return s;
}

std::string to_text(const GeometrySummary& s) {
  std::ostringstream t;
  t << std::fixed << std::setprecision(2) << "source to volume origin " << s.source_to_origin_mm << " mm, to detector "
    << s.source_to_detector_mm << " mm, magnification " << std::setprecision(4) << s.magnification << " (medians over " << s.views
    << " views)\n"
    << std::setprecision(2) << "cone " << s.cone_angle_u_deg << " x " << s.cone_angle_v_deg
    << " deg (columns x rows), field of view at the origin " << s.field_of_view_u_mm << " x " << s.field_of_view_v_mm << " mm\n"
    << std::setprecision(4) << "a pixel at the origin: " << s.voxel_mm << " mm (a voxel to start from: --voxel " << s.voxel_mm
    << ")\n";
  return t.str();
}

}  // namespace ctk

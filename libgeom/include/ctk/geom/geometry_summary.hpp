#pragma once
// What a scan's geometry means for a reconstruction, from its per-view matrices alone: how far
// the source is from the volume's origin, how far from the detector, the magnification there,
// the cone's opening, the field of view at the origin and the voxel that matches a pixel. Medians
// over the posed views (a robot trajectory varies them).
#include <string>

#include "ctk/geom/geometry_file.hpp"

namespace ctk {

struct GeometrySummary {
  int views = 0;  // views with a matrix
  double source_to_origin_mm = 0, source_to_detector_mm = 0, magnification = 0;
  double cone_angle_u_deg = 0, cone_angle_v_deg = 0;      // full opening across columns and rows
  double field_of_view_u_mm = 0, field_of_view_v_mm = 0;  // the detector's extent at the origin
  double voxel_mm = 0;                                    // a column's pitch at the origin
};

/// The medians over the views with a matrix; views == 0 when none has one.
GeometrySummary summarize_geometry(const Geometry& g);

/// Three lines for a person: distances and magnification, cone and field of view, the voxel.
std::string to_text(const GeometrySummary& s);

}  // namespace ctk

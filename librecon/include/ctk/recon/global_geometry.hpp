#pragma once
// Effects shared by every view of a circular scan that change where the rays go, as corrections
// to the nominal per-view matrices (markerless refinement fits them; see markerless_refinement.hpp):
//   detector_offset  the detector shifted in its plane: principal point and the axis' column move
//   detector_roll    the detector rotated in its plane about the principal point
//   axis_tilt        the rotation axis tilted towards the source (about each view's column
//                    direction through the orbit centre; a tilt across the beam is a roll)
//   magnification    the source-to-detector distance scaled (zoom about the principal point)
// and the forward model's angular blur: a view integrating an arc of continuous rotation is the
// mean of sub-views spread over that arc.
#include <vector>

#include "ctk/geom/projection_matrix.hpp"
#include "ctk/recon/fdk.hpp"

namespace ctk {

struct GlobalGeometry {
  double du_px = 0, dv_px = 0;  // detector_offset
  double roll_rad = 0;          // detector_roll
  double tilt_rad = 0;          // axis_tilt
  double sdd_scale = 1;         // magnification
};

/// The nominal matrices with the effects applied. `orbit` is the circle the nominal sources lie on.
std::vector<ProjectionMatrix> apply_global_geometry(const GlobalGeometry& g, const std::vector<ProjectionMatrix>& nominal,
                                                    const CircularTrajectory& orbit);

/// `samples` sub-views of P spread evenly over an arc of rotation about the orbit's axis (centred
/// on P's angle): the mean of their projections models a view exposed during continuous rotation.
std::vector<ProjectionMatrix> angular_sub_views(const ProjectionMatrix& P, const CircularTrajectory& orbit, double arc_rad,
                                                int samples);

}  // namespace ctk

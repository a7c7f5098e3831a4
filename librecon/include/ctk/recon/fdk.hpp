#pragma once
// FDK (Feldkamp-Davis-Kress) for the circular scans users still run, with the geometry taken
// from the per-view matrices: the source positions must lie on a circle (else FDK is refused
// with the numbers), the rotation axis must appear along the detector's v direction (rows are
// ramp-filtered), and a scan covering less than a full turn gets Parker redundancy weights
// generalised to any arc between pi + fan and 2 pi (Wesarg et al. 2002).
#include <vector>

#include "ctk/core/projection_stack.hpp"
#include "ctk/core/volume.hpp"
#include "ctk/geom/detector.hpp"
#include "ctk/geom/projection_matrix.hpp"

namespace ctk {

struct CircularTrajectory {
  Eigen::Vector3d centre{0, 0, 0};             // of the source circle (holder frame)
  Eigen::Vector3d axis{0, 0, 1};               // unit normal of its plane; angles turn right-handed about it
  double radius_mm = 0;                        // source to rotation axis
  std::vector<double> angles_rad;              // per view, measured from the first view, in [0, 2 pi)
  std::vector<double> step_rad;                // angular weight of each view (half the gaps to its neighbours)
  double arc_rad = 0;                          // covered arc (2 pi for a full turn)
  double off_plane_mm = 0, off_circle_mm = 0;  // largest deviations of a source from the fit
};

/// Throws std::invalid_argument describing the deviation when the sources are not on a circle
/// (more than max(1 mm, 0.2 % of the radius) off its plane or off the circle).
CircularTrajectory fit_circular_trajectory(const std::vector<ProjectionMatrix>& views);

/// Parker weight of the ray at fan angle gamma (signed about the axis, from the central ray) in the
/// view at angle beta of a scan covering `arc` (pi + 2 delta, delta >= |gamma|): conjugate rays
/// (beta, gamma) and (beta + pi + 2 gamma, -gamma) sum to 1.
double parker_weight(double beta, double gamma, double arc);

enum class RampWindow { ram_lak, hann };

/// Reconstructs into `x` (its layout is kept). `line_integrals` is filtered in place.
void fdk_reconstruct(const std::vector<ProjectionMatrix>& views, ProjectionStack& line_integrals, const Detector& detector,
                     Volume& x, RampWindow window = RampWindow::hann);

}  // namespace ctk

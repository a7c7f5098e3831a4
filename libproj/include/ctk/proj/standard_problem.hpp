#pragma once
// The projector benchmark's standard problem: a 256^3 volume of 1 mm voxels, a 256 x 256
// detector of 1.6 mm pixels, source 1000 mm from the isocentre and 1500 mm from the detector,
// 360 views on a circle (about the volume's z axis) or spread over the sphere.
#include <string>
#include <vector>

#include "ctk/core/volume.hpp"
#include "ctk/geom/projection_matrix.hpp"

namespace ctk {

enum class StandardTrajectory { circular, spherical };

struct StandardProblem {
  VolumeLayout layout;
  int rows = 0, cols = 0;
  std::vector<ProjectionMatrix> views;
  std::string trajectory;
};

/// `scale` divides every size (volume, detector) for quick runs; 1 is the standard problem.
StandardProblem standard_problem(StandardTrajectory trajectory, int views = 360, int scale = 1);

}  // namespace ctk

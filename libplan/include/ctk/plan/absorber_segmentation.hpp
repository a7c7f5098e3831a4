#pragma once
// Which parts of a coarse reconstruction are dense enough to spoil the views that look through
// them. Only the sample's region counts (inside the holder's bore: the tube and its spheres are
// blanked). The yardstick is the holder itself: its POM wall is in every scan, reconstructed with
// the same spectrum, blur and noise as the sample, so "denser than twice the wall" means the same
// thing whatever the tube voltage (beam hardening raises every level alike) and picks out metals
// and thick dense parts, not plastics, wood or a walnut's shell. A coarse volume's noise reaches
// about half the wall's level; a handful of voxels above the threshold is noise, not an absorber.
#include <string>

#include "ctk/core/volume.hpp"

namespace ctk {

struct SampleRegion {
  double radius_mm = 23.5;       // about the holder axis (+w): the reference holder's bore is 25 mm
  double half_height_mm = 45.0;  // along the axis, about the holder origin
  bool contains(const Eigen::Vector3d& p) const;
};

struct SegmentationOptions {
  SampleRegion region;
  double wall_inner_mm = 25.5, wall_outer_mm = 27.5;  // inside the reference holder's 3 mm POM wall
  double times_wall = 2.0;                            // absorbers attenuate more than this many times the wall
  std::size_t min_voxels = 20;                        // fewer above the threshold: noise, nothing segmented
  void validate() const;                              // std::invalid_argument naming the field
};

struct AbsorberSegmentation {
  Volume absorbers;       // 1 inside absorbers, 0 elsewhere (same layout as the input)
  double wall_level = 0;  // median of the holder wall's voxels, 1/mm
  double threshold = 0;   // 1/mm
  std::size_t voxels = 0;
  std::string note;  // why nothing was segmented
};

AbsorberSegmentation segment_absorbers(const Volume& reconstruction, const SegmentationOptions& options = {});

}  // namespace ctk

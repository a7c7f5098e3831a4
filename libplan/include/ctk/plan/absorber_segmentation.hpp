#pragma once
// Which parts of a coarse reconstruction are dense enough to spoil the views that look through
// them. Only the sample's region counts (inside the holder's bore: the tube and its spheres are
// blanked). Rule: the absorbers' level is a high percentile of that region, the bulk's the median
// of the material voxels (above a tenth of the high level); when the two differ by at least
// `min_contrast`, voxels above the midpoint between them are absorbers. A sample without such a
// contrast has no absorbers and every direction scores alike.
#include <string>

#include "ctk/proj/volume.hpp"

namespace ctk {

struct SampleRegion {
  double radius_mm = 23.5;       // about the holder axis (+w): the reference holder's bore is 25 mm
  double half_height_mm = 45.0;  // along the axis, about the holder origin
  bool contains(const Eigen::Vector3d& p) const;
};

struct SegmentationOptions {
  SampleRegion region;
  double high_percentile = 99.95;// of the region's voxels: the absorbers' level
  double min_contrast = 2.5;      // high level / bulk level needed to call anything an absorber
};

struct AbsorberSegmentation {
  Volume absorbers;             // 1 inside absorbers, 0 elsewhere (same layout as the input)
  double bulk_level = 0;        // 1/mm
  double high_level = 0;        // 1/mm
  double threshold = 0;         // 1/mm; 0 when nothing was segmented
  std::size_t voxels = 0;
  std::string note;             // why nothing was segmented
};

AbsorberSegmentation segment_absorbers(const Volume& reconstruction, const SegmentationOptions& options = {});

}  // namespace ctk

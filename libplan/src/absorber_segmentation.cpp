#include "ctk/plan/absorber_segmentation.hpp"

#include <algorithm>
#include <cmath>
#include <vector>

#include "ctk/core/error.hpp"
#include "ctk/core/statistics.hpp"

namespace ctk {

bool SampleRegion::contains(const Eigen::Vector3d& p) const {
  return p.head<2>().norm() <= radius_mm && std::abs(p.z()) <= half_height_mm;
}

void SegmentationOptions::validate() const {
  require_option(region.radius_mm > 0, "SegmentationOptions.region.radius_mm", "a number above 0", region.radius_mm);
  require_option(region.half_height_mm > 0, "SegmentationOptions.region.half_height_mm", "a number above 0",
                 region.half_height_mm);
  require_option(wall_inner_mm > 0, "SegmentationOptions.wall_inner_mm", "a number above 0", wall_inner_mm);
  require_option(wall_outer_mm > wall_inner_mm, "SegmentationOptions.wall_outer_mm", "a radius beyond wall_inner_mm",
                 wall_outer_mm);
  require_option(times_wall > 0, "SegmentationOptions.times_wall", "a number above 0", times_wall);
  require_option(min_voxels >= 1, "SegmentationOptions.min_voxels", "at least 1", static_cast<double>(min_voxels));
}

AbsorberSegmentation segment_absorbers(const Volume& x, const SegmentationOptions& options) {
  options.validate();
  AbsorberSegmentation s{Volume(x.layout), 0, 0, 0, {}};
  const auto& n = x.layout.size;
  std::vector<std::size_t> inside;
  std::vector<float> wall;
  for (int k = 0; k < n[2]; ++k)
    for (int j = 0; j < n[1]; ++j)
      for (int i = 0; i < n[0]; ++i) {
        const Eigen::Vector3d p = x.layout.centre_of(i, j, k);
        const double r = p.head<2>().norm();
        if (options.region.contains(p))
          inside.push_back(x.index(i, j, k));
        else if (r >= options.wall_inner_mm && r <= options.wall_outer_mm && std::abs(p.z()) <= options.region.half_height_mm)
          wall.push_back(x.at(i, j, k));
      }
  if (wall.empty()) {
    s.note = "the holder's wall is not in the volume: no yardstick for absorbers";
    return s;
  }
  s.wall_level = median_in_place(wall);
  if (!(s.wall_level > 0)) {
    s.note = "the holder's wall is not reconstructed yet";
    return s;
  }
  s.threshold = options.times_wall * s.wall_level;
  for (std::size_t i : inside)
    if (x.data[i] > s.threshold) {
      s.absorbers.data[i] = 1.0f;
      ++s.voxels;
    }
  if (s.voxels < options.min_voxels) {
    s.note = "no absorbers: " + std::to_string(s.voxels) + " voxels above " + std::to_string(options.times_wall) +
             " times the holder wall's " + std::to_string(s.wall_level) + "/mm";
    std::fill(s.absorbers.data.begin(), s.absorbers.data.end(), 0.0f);
    s.voxels = 0;
  }
  return s;
}

}  // namespace ctk

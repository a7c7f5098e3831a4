#include "ctk/plan/planner_picture.hpp"

#include <algorithm>
#include <cmath>

#include "ctk/plan/picture_median.hpp"

namespace ctk {
namespace {

// The voxels a reading looks at: the sample region and the holder wall (the segmentation's
// yardstick) within the region's height, and one more on every side for the gradients' stencil.
// Filtering only these makes the median a third of the cost on the planner's 128^3 grid.
VoxelBox read_box(const VolumeLayout& l, const SegmentationOptions& s) {
  const double r = std::max(s.region.radius_mm, s.wall_outer_mm);
  const Eigen::Vector3d reach(r, r, s.region.half_height_mm);
  VoxelBox box;
  for (std::size_t a = 0; a < 3; ++a) {
    const auto e = static_cast<Eigen::Index>(a);
    box.lo[a] = static_cast<int>(std::floor((-reach[e] - l.origin_mm[e]) / l.voxel_mm[e])) - 1;
    box.hi[a] = static_cast<int>(std::ceil((reach[e] - l.origin_mm[e]) / l.voxel_mm[e])) + 2;
  }
  return box;
}

}  // namespace

void PlannerPicture::give_to(ViewPlanner& planner) const {
  planner.set_damage(segmentation.voxels > 0 ? damage_mm : std::vector<double>{});
  planner.set_edge_demand(edge_demand);
}

PlannerPicture read_planner_picture(const Volume& picture, const std::vector<Eigen::Vector3d>& candidates,
                                    const PictureReading& reading, const DamageGeometry& geometry) {
  const Volume filtered = reading.median ? median_3x3x3(picture, read_box(picture.layout, reading.segmentation)) : Volume{};
  const Volume& read = reading.median ? filtered : picture;
  PlannerPicture p;
  p.segmentation = segment_absorbers(read, reading.segmentation);
  for (const DirectionDamage& d : direction_damage(p.segmentation, candidates, geometry))
    p.damage_mm.push_back(d.longest_path_mm);
  if (reading.edge_demand)
    p.edge_demand = tangent_edge_demand(read, reading.segmentation.region, candidates, reading.edge_tangency);
  return p;
}

}  // namespace ctk

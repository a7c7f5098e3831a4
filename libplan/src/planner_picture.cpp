#include "ctk/plan/planner_picture.hpp"

#include "ctk/plan/picture_median.hpp"

namespace ctk {

void PlannerPicture::give_to(ViewPlanner& planner) const {
  planner.set_damage(segmentation.voxels > 0 ? damage_mm : std::vector<double>{});
  planner.set_edge_demand(edge_demand);
}

PlannerPicture read_planner_picture(const Volume& picture, const std::vector<Eigen::Vector3d>& candidates,
                                    const PictureReading& reading, const DamageGeometry& geometry) {
  const Volume filtered = reading.median ? median_3x3x3(picture) : Volume{};
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

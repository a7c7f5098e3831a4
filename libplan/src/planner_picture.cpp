#include "ctk/plan/planner_picture.hpp"

#include "ctk/plan/picture_median.hpp"

namespace ctk {

void PlannerPicture::give_to(ViewPlanner& planner) const {
  planner.set_damage(segmentation.voxels > 0 ? damage_mm : std::vector<double>{});
  planner.set_edge_demand(edge_demand);
}

PlannerPicture read_planner_picture(const Volume& picture, const std::vector<Eigen::Vector3d>& candidates,
                                    const SegmentationOptions& segmentation, const EdgeTangencyOptions& edge_tangency,
                                    bool with_edge_demand, const DamageGeometry& geometry) {
  const Volume clean = median_3x3x3(picture);
  PlannerPicture p;
  p.segmentation = segment_absorbers(clean, segmentation);
  for (const DirectionDamage& d : direction_damage(p.segmentation, candidates, geometry))
    p.damage_mm.push_back(d.longest_path_mm);
  if (with_edge_demand) p.edge_demand = tangent_edge_demand(clean, segmentation.region, candidates, edge_tangency);
  return p;
}

}  // namespace ctk

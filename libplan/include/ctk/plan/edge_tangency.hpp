#pragma once
// Which view directions the sample's edges need. A jump in attenuation across a surface is
// measured sharply only by rays that graze it: a view whose rays cross the surface spreads the
// jump over the shadow, one whose rays run along it sees a step. So a trajectory that thins out
// the directions tangent to a strong edge leaves that edge blurred and streaked. On sample 1 a
// trajectory without views within 10 deg of its aluminium plate's plane scored an RMSE of
// 0.0095 /mm, and one with a third of its views there 0.0071, against 0.0075 for the whole
// sphere (README, "Planning").
//
// The demand of a direction d is the sum over the voxels of the region of |grad mu|^2 phi(n . d),
// n the unit gradient (the edge's normal) and phi(c) = exp(-(c / sin w)^2), which keeps the
// directions within about w of the edge's tangent plane. The jump is squared because the squared
// error a blurred edge leaves grows with it. Gradients are binned by direction on a HEALPix sphere
// first, so the cost is one pass over the volume plus cells x directions.
#include <Eigen/Core>
#include <vector>

#include "ctk/core/volume.hpp"
#include "ctk/plan/absorber_segmentation.hpp"

namespace ctk {

struct EdgeTangencyOptions {
  double tangent_width_deg = 10;  // w
  int normal_nside = 8;           // HEALPix sphere the edge normals are binned on
  void validate() const;          // std::invalid_argument naming the field
};

/// Per direction, its demand relative to the mean demand over `directions` (1 everywhere when
/// the region has no gradient at all). `directions` should cover the sphere evenly (HEALPix
/// cells), or the mean is not the sphere's.
std::vector<double> tangent_edge_demand(const Volume& volume, const SampleRegion& region,
                                        const std::vector<Eigen::Vector3d>& directions, const EdgeTangencyOptions& options = {});

}  // namespace ctk

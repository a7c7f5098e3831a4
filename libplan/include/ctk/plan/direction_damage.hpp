#pragma once
// How much a view direction would suffer from the absorbers: the segmented absorbers are forward
// projected (Joseph) through a virtual view looking along the direction, and the image of path
// lengths through them is summarised. What wrecks a projection is a long path through dense
// material (photon starvation, beam hardening), not the shadow's area alone, so the damage is the
// longest path (the mean of the top 1 % of shadow pixels, robust to a single voxel); the shadow's
// share of the detector is reported beside it.
#include <vector>

#include "ctk/geom/projection_matrix.hpp"
#include "ctk/plan/absorber_segmentation.hpp"

namespace ctk {

struct DamageGeometry {
  double source_to_isocentre_mm = 1360;
  double source_to_detector_mm = 2150;
  int detector_pixels = 64;  // square virtual detector; its pitch is chosen to frame the absorbers
};

struct DirectionDamage {
  double longest_path_mm = 0;
  double shadow_fraction = 0;  // of the virtual detector's pixels
};

/// The view that looks along `direction` (holder frame) with the holder origin at the isocentre.
ProjectionMatrix virtual_view(const Eigen::Vector3d& direction, const Intrinsics& K, double source_to_isocentre_mm);

/// One entry per direction; all zero when nothing was segmented.
std::vector<DirectionDamage> direction_damage(const AbsorberSegmentation& segmentation,
                                              const std::vector<Eigen::Vector3d>& directions,
                                              const DamageGeometry& geometry = {});

}  // namespace ctk

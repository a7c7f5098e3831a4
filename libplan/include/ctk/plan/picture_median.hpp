#pragma once
// The planner's picture with its noise and thin streaks taken out: each voxel replaced by the
// median of its 3 x 3 x 3 neighbourhood (at the border, the neighbourhood clamped to the volume).
// The coarse reconstruction the planner reads is made of few CG iterations on binned views; its
// noise and the streaks of few views have gradients in every direction, which flatten the edges'
// demand (edge_tangency.hpp) towards the even spread and pull views to false edges. A median
// keeps a step between two regions at least two voxels thick where it was and removes what is
// thinner. Drawing from its own pictures read this way, the planner's rule gained +4.3 % over the
// whole sphere (levels matched), +2.7 % from them as they are, +4.6 % from the truth; through the
// lab on 24 held-out samples +6.4 % against +2.3 % (docs/planning/README.md, "A cleaner picture";
// benchmarks/planning_picture_reading.py, planning_population.py).
#include <array>

#include "ctk/core/volume.hpp"

namespace ctk {

/// Voxels lo <= (i, j, k) < hi, per axis.
struct VoxelBox {
  std::array<int, 3> lo{0, 0, 0}, hi{0, 0, 0};
};

/// The median of every voxel.
Volume median_3x3x3(const Volume& volume);
/// The median of the voxels in `box` (clipped to the volume), the others copied: what a reader
/// that never looks outside the box needs, at the box's share of the cost.
Volume median_3x3x3(const Volume& volume, const VoxelBox& box);

}  // namespace ctk

#pragma once
// The grid a reconstruction uses when the user does not choose one: voxels the size of a detector
// pixel seen at the holder origin, covering the helix holder when the scan declares one, else the
// detector's field of view.
#include <vector>

#include "ctk/core/volume.hpp"
#include "ctk/geom/scan.hpp"

namespace ctk {

/// Median distance from the source to the holder origin over the views.
double median_source_distance(const std::vector<ProjectionMatrix>& views);

/// `voxel_mm` <= 0: a pixel seen at the holder origin, times `coarsening`.
VolumeLayout default_volume_layout(const ScanDescription& scan, const std::vector<ProjectionMatrix>& views, double voxel_mm = 0,
                                   double coarsening = 1.0);

}  // namespace ctk

#pragma once
// Private to libproj: how the fast projector deals the views' detector lines into ray tables.
// A line's rays lie in one plane through the source (LanePath); a run of neighbouring lines
// covers a slab of the volume between two such planes. Lines of different views whose planes
// nearly coincide go through the same voxels, so the tables take, for one slab of the volume at a
// time, each view's lines through that slab, the views ordered so that neighbours' slabs tilt
// alike: neighbouring tables and the views of one table then write (and read) the same voxels.
#include <vector>

#include "ctk/proj/ray_geometry.hpp"
#include "ray_table.hpp"

namespace ctk::detail {

// Lines [line_begin, line_begin + lines) of view `view`.
struct LineRange {
  int view = 0, line_begin = 0, lines = 0;
};

struct SlabLines {
  int capacity = 0;                           // most lines of one view in one slab: the tables' rows
  std::vector<std::vector<LineRange>> slabs;  // per slab, the lines of each view crossing it, in slab order
};

/// The slabs, each about `rows_per_block` lines of the view with the densest lines thick, and
/// every view's lines through each. Views come in slab order: by the dominant axis of their
/// central ray, then by the tilt of their lines' planes about the axis their lanes run along,
/// then by heading; or as given where that is as coherent (circular trajectories).
SlabLines slab_lines(const std::vector<ViewRays>& rays, const std::vector<LanePath>& paths, const VolumeLayout& layout,
                     int rows_per_block);

}  // namespace ctk::detail

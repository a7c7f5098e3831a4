#pragma once
// Voxel-driven back projection, the kind filtered back projection (FDK) uses: each voxel centre X
// is projected by every view's matrix, reads that view's image bilinearly at P X (zero off the
// detector), and adds it weighted by (scale / depth)^2, depth = the third row of P X (mm, P
// normalised). It is not the adjoint of the Joseph projector; the CG solvers use that one.
#include <vector>

#include "ctk/core/projection_stack.hpp"
#include "ctk/core/volume.hpp"
#include "ctk/geom/projection_matrix.hpp"

namespace ctk {

/// x = sum over views of (scale_mm / depth)^2 q_v(P_v X) (x's layout kept, values overwritten).
/// Voxels behind a view's source take nothing from it. SIMD across a row of voxels, threads own
/// z slices.
void voxel_backproject(const ProjectionStack& q, const std::vector<ProjectionMatrix>& views, double scale_mm, Volume& x);

/// The same in plain scalar double precision on one thread: the oracle of the tests and the
/// baseline of the benchmark.
void voxel_backproject_reference(const ProjectionStack& q, const std::vector<ProjectionMatrix>& views, double scale_mm,
                                 Volume& x);

}  // namespace ctk

#pragma once
// The naive Joseph projector: scalar, single thread, double precision, one ray at a time. It is
// the oracle of the tests and the baseline of the benchmark, so it is written to be obviously
// right rather than fast (but compiled with the same flags as everything else).
#include <vector>

#include "ctk/core/projection_stack.hpp"
#include "ctk/core/volume.hpp"
#include "ctk/geom/projection_matrix.hpp"

namespace ctk {

/// y = A x: one view of `y` per matrix (y must be sized views x rows x cols).
void forward_project_reference(const Volume& x, const std::vector<ProjectionMatrix>& views, ProjectionStack& y);
/// x = A' y (x's layout is kept, its values overwritten).
void back_project_reference(const ProjectionStack& y, const std::vector<ProjectionMatrix>& views, Volume& x);

}  // namespace ctk

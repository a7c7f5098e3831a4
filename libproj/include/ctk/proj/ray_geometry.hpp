#pragma once
// Per-view ray geometry in voxel-index coordinates, shared by every projector. For pixel (u, v)
// the ray leaves the source c along d(u, v) = d0 + u du + v dv; both in index units (voxel
// (i, j, k) centre at index (i, j, k)). Joseph's method steps one slice along the ray's dominant
// axis; each sample weighs the physical path length (mm) between slices.
#include <array>
#include <vector>

#include "ctk/core/projection_stack.hpp"
#include "ctk/core/volume.hpp"
#include "ctk/geom/projection_matrix.hpp"

namespace ctk {

struct ViewRays {
  Eigen::Vector3d source;  // index coordinates
  Eigen::Vector3d d0, du, dv;
};

ViewRays view_rays(const ProjectionMatrix& P, const VolumeLayout& layout);

/// One ray prepared for marching along its dominant axis a. At slice k the sample sits at
/// (p_b, p_c) = (pb_mid + (k - k_mid) beta_b, pc_mid + (k - k_mid) beta_c), with b < c the other
/// two axes; k_mid = (n_a - 1) / 2 keeps the numbers small (float-safe). Samples k in
/// [k_first, k_last] may touch the volume (outside it, bilinear corners read as zero).
struct MarchedRay {
  int axis = 0;
  double pb_mid = 0, beta_b = 0, pc_mid = 0, beta_c = 0;
  double weight_mm = 0;          // path length per slice
  int k_first = 0, k_last = -1;  // empty when k_last < k_first
};

MarchedRay march_ray(const ViewRays& rays, const VolumeLayout& layout, double u, double v);

/// Every projector's precondition: one view of `y` per matrix, a non-empty detector.
void check_stack_matches_views(int stack_views, int rows, int cols, std::size_t view_count);

/// The two non-dominant axes (b < c) of `axis`.
inline std::array<int, 2> other_axes(int axis) {
  return axis == 0 ? std::array<int, 2>{1, 2} : axis == 1 ? std::array<int, 2>{0, 2} : std::array<int, 2>{0, 1};
}

}  // namespace ctk

#pragma once
// Private to libproj: the rays of a few detector rows, in float, structure-of-arrays so that
// SIMD lanes load neighbouring rays at once. Both fast kernels read the same table.
#include <cstdint>
#include <vector>

#include "ctk/proj/ray_geometry.hpp"

namespace ctk::detail {

inline constexpr int kMaxLanes = 16;  // widest float vector (AVX-512); tables are padded to it

struct RayTable {
  int count = 0;   // rays in use (padded up to a multiple of kMaxLanes with empty rays)
  std::vector<float> pb_mid, beta_b, pc_mid, beta_c, weight, k_mid, value;
  std::vector<std::int32_t> k_first, k_last, axis, stride_a, stride_b, stride_c, n_b, n_c;

  void resize(int capacity);
  /// Rays numbered from pixel (0, row_begin), row by row over `cols` columns; fills entries
  /// offset + [ray_begin, ray_end) only, so threads can fill one table together, and several
  /// views can share a table (each at its own offset).
  void fill(const ViewRays& rays, const VolumeLayout& layout, int row_begin, int cols, int ray_begin, int ray_end,
            int offset = 0);
  /// Marks entries [begin, end) empty.
  void empty(int begin, int end);
  /// Uses `used` rays: count becomes the next multiple of kMaxLanes, the rest marked empty.
  void pad(int used);
};

// Kernels (Highway, dispatched to the widest SIMD unit at run time).
/// out[r] = line integral of ray r, for r in [0, table.count) (a multiple of kMaxLanes).
void forward_rays(const RayTable& table, const float* volume, float* out);
/// volume += A' y for the rays of dominant `axis`, slices [k_begin, k_end) only; y is
/// table.value (each ray's projection value).
void back_rays(const RayTable& table, int axis, int k_begin, int k_end, float* volume);
const char* simd_target_name();
int simd_float_lanes();

}  // namespace ctk::detail

#pragma once
// Private to libproj: the rays of a few detector rows of one or more views, in float,
// structure-of-arrays so that SIMD lanes load neighbouring rays at once. Each detector row is
// padded to a multiple of kMaxLanes, so a SIMD bundle never straddles two rows and the bundles
// of one column strip in consecutive rows march through neighbouring voxels. Both fast kernels
// read the same table.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include "ctk/proj/ray_geometry.hpp"

namespace ctk::detail {

inline constexpr int kMaxLanes = 16;  // widest float vector (AVX-512); rows are padded to it
// Lines per table for views whose rays cross the rows of their slices
// (JosephProjector::default_rows_per_block); the kernels' strips hold that many rows.
inline constexpr int kLinesAcrossRows = 24;
// Slices of x per tile chunk for rays along x (joseph_tiles-inl.h): 16 floats, a 64-byte line
// where the volume's rows start on one. Chunks start at multiples of it, and so do the back
// projection's slabs along x where they are that wide (slab_edge).
inline constexpr int kTileSlices = 16;

// What a kernel needs to know about one bundle of N neighbouring rays before marching it.
struct Bundle {
  std::size_t r = 0;          // first entry
  int k_lo = 0, k_hi = -1;    // slices any lane visits
  int in_lo = 0, in_hi = -1;  // slices on the fast path (interior_range)
  bool pairs = false;         // corners b and b + 1 adjacent in memory for every lane
  bool window = false;        // pairs, one axis for every lane: rows of the slice can be loaded whole
  int axis = -2;              // the dominant axis every lane shares; -2 when they differ
};

// How one view's detector pixels are dealt out to table rows, so that a bundle's rays stay in
// one row of every slice. Lanes step along the major detector axis (u or v) and, in a staircase,
// `slope` minor pixels per lane: the detector direction along which a ray's sample moves along
// the other axis b only (the contiguous one, in the volume or in a tile) of the view's dominant
// axis. Lane l of line j is the pixel (major m = major_first + l, minor line_first + j +
// round(m slope)); the lines partition the pixels of the volume's footprint. Pixels the staircase
// puts outside the detector still get their rays (the bundle stays whole), but are never read or
// written; pixels outside the footprint are in no line (their rays miss the volume).
// One path per view, for the dominant axis at the detector's centre. In a view between two axes
// the other axis's lanes then spread over several rows and gather; a path per axis removed
// those gathers but measured no faster (benchmarks/README.md, benchmarks/paired.py).
struct LanePath {
  Eigen::Vector3d central_ray = Eigen::Vector3d::UnitZ();  // the ray through the detector's centre
  int axis = 2;                                            // its dominant axis, the one the path is chosen for
  bool along_u = true;                                     // the major axis is u (columns)
  double slope = 0;                                        // minor pixels per lane, |slope| <= 1
  int major_first = 0, majors = 1;                         // the footprint's pixels along the major axis (lanes per line)
  int minors = 1;                                          // detector pixels along the minor axis
  int line_first = 0, lines = 1;                           // line numbers in use (none when the footprint misses the detector)
  bool whole_detector = true;                              // the footprint holds every pixel: the lines cover the detector
  // The pixels whose rays can touch the volume: the bounding rectangle of the volume's box, grown
  // by a voxel (bilinear samples reach that far), projected on the detector. Rays elsewhere
  // project to zero and are never prepared (a small volume on a large detector would otherwise
  // pay for every pixel's ray). Everything when part of that box lies behind the source.
  double u_lo = -1e300, u_hi = 1e300, v_lo = -1e300, v_hi = 1e300;

  /// The path for a view of cols x rows pixels, chosen at the detector's centre.
  static LanePath for_view(const ViewRays& rays, const VolumeLayout& layout, int cols, int rows);
  int minor(int line, int lane) const {
    return line_first + line + static_cast<int>(std::floor((major_first + lane) * slope + 0.5));
  }
  /// Pixel (u, v) of lane `lane` of line `line` (0 = the first line), inside the detector or not.
  void pixel(int line, int lane, int& u, int& v) const {
    const int m = minor(line, lane);
    u = along_u ? major_first + lane : m;
    v = along_u ? m : major_first + lane;
  }
  bool inside(int line, int lane) const {
    const int m = minor(line, lane);
    return lane >= 0 && lane < majors && m >= 0 && m < minors;
  }
  /// Whether any of lanes [lane, lane + count) of the line is inside the detector, with the
  /// lanes' rectangle of pixels meeting the volume's footprint.
  bool meets_detector(int line, int lane, int count) const;

 private:
  void find_footprint(const ViewRays& rays, const VolumeLayout& layout);
};

struct RayTable {
  int views = 0;        // views in use, each at slot * view_stride
  int rows = 0;         // detector rows in use per view (fewer where slot_rows says so)
  int row_stride = 0;   // entries per row: the lanes rounded up to kMaxLanes
  int view_stride = 0;  // entries per view: the row capacity times row_stride
  // Rows in use in each slot, where fewer than `rows` (a view whose lines end before the
  // others' in a shared back-projection table): the kernels skip the rest, which need not be
  // filled or emptied.
  std::vector<int> slot_rows;
  int rows_in(int slot) const { return std::min(rows, slot_rows[static_cast<std::size_t>(slot)]); }
  std::vector<float> pb_mid, beta_b, pc_mid, beta_c, weight, k_mid, value;
  std::vector<std::int32_t> k_first, k_last, axis, stride_a, stride_b, stride_c, n_b, n_c;
  // Slices where all four corners of the entry's sample are inside the grid (by 1e-3 voxel):
  // no masks needed there. Empty (in_first > in_last) when none.
  std::vector<std::int32_t> in_first, in_last;
  // The grid the kernels address: voxel (k, b, c) of the rays' axes is at
  // (k - origin_a) stride_a + (b - origin_b) stride_b + (c - origin_c) stride_c, and only
  // 0 <= b - origin_b < n_b, 0 <= c - origin_c < n_c exist. Zero for the volume itself; a
  // tile's corner when the rays are marched through a transposed copy of part of it.
  int origin_a = 0, origin_b = 0, origin_c = 0;
  /// Bundle i (entries [i N, i N + N), N the SIMD width) as prepare_bundles found it, for tables
  /// that many slab tasks read (back projection): found once, not once per slab.
  std::vector<Bundle> bundles;

  /// Room for `views` views of `rows` rows of `lanes` lanes; views and rows in use are set to that.
  void shape(int views, int rows, int lanes);
  std::size_t entry(int slot, int row, int col) const {
    return static_cast<std::size_t>(slot) * static_cast<std::size_t>(view_stride) +
           static_cast<std::size_t>(row) * static_cast<std::size_t>(row_stride) + static_cast<std::size_t>(col);
  }
  /// The rays of lines [line_begin, line_begin + rows) of one view in slot `slot`, numbered
  /// r = row * row_stride + lane; fills r in [ray_begin, ray_end) only, so threads can fill one
  /// table together. Bundles with no pixel on the detector are left empty.
  void fill(const ViewRays& rays, const VolumeLayout& layout, int slot, const LanePath& path, int line_begin, int ray_begin,
            int ray_end);
  /// Marks entries [begin, end) empty: they touch nothing and project to zero.
  void empty(std::size_t begin, std::size_t end);
};

/// Up to kMaxLanes rays as march_ray prepares them, with the interior range (in_first, in_last:
/// slices where all four corners of the sample, as the float table holds it, are inside the
/// grid by 1e-3 voxel). Integers are held as doubles.
struct PreparedRays {
  double axis[kMaxLanes], pb_mid[kMaxLanes], beta_b[kMaxLanes], pc_mid[kMaxLanes], beta_c[kMaxLanes];
  double weight_mm[kMaxLanes], k_first[kMaxLanes], k_last[kMaxLanes], in_first[kMaxLanes], in_last[kMaxLanes];
};
/// The rays through pixels (u[l], v[l]), l < count <= kMaxLanes (u and v readable up to
/// kMaxLanes), SIMD across rays; origin_b and origin_c are the table's grid origin.
void prepare_rays(const ViewRays& rays, const VolumeLayout& layout, int origin_b, int origin_c, const double* u, const double* v,
                  int count, PreparedRays& out);
/// The pixels (u[l], v[l]) of lanes lane + min(l, count - 1), l < kMaxLanes, of a line (as
/// LanePath::pixel finds them), for prepare_rays.
void lane_pixels(const LanePath& path, int line, int lane, int count, double* u, double* v);
/// Entries [first, first + count) of `table` from p (count <= kMaxLanes), as fill() stores them.
void store_rays(const PreparedRays& p, const VolumeLayout& layout, int count, RayTable& table, std::size_t first);

// Kernels (Highway, dispatched to the widest SIMD unit at run time).
/// out[e] = line integral of the ray at entry e, for every entry in use (out sized like the table).
void forward_rays(const RayTable& table, const float* volume, float* out);
/// volume += A' y for the rays of dominant `axis`, slices [k_begin, k_end) only; y is
/// table.value (each ray's projection value).
void back_rays(const RayTable& table, int axis, int k_begin, int k_end, float* volume);
/// Fills table.bundles for bundles [begin, end) (count: bundle_count()), from their filled
/// entries (bundles in rows a slot does not use are left as they are).
void prepare_bundles(RayTable& table, std::size_t begin, std::size_t end);
std::size_t bundle_count(const RayTable& table);
const char* simd_target_name();
int simd_float_lanes();

}  // namespace ctk::detail

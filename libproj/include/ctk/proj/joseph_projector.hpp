#pragma once
// The fast Joseph projector: the same discretisation as the reference (ray_geometry.hpp), with
// SIMD across neighbouring rays (Highway, widest unit found at run time: AVX-512, AVX2, SSE4, ...)
// and OpenMP threads. Its back projection is the exact adjoint of its forward projection: both
// walk the same float ray tables and compute every sample weight with the same operations.
//
// Threads never write the same voxel: the back projection takes a few detector lines at a time,
// and splits the volume into slabs along each ray's dominant axis (a Joseph sample at slice k
// touches only slice k), one slab per task. Extra memory: a table of a few rows and a tile per
// thread forward; back, two shared tables of about 4.5 MB and a band of up to 1 MB per thread.
#include <string>
#include <vector>

#include "ctk/core/projection_stack.hpp"
#include "ctk/core/volume.hpp"
#include "ctk/geom/projection_matrix.hpp"

namespace ctk {

struct ProjectorOptions {
  int threads = 0;         // 0: all OpenMP threads
  int rows_per_block = 0;  // detector lines of a view per ray table (rows, or staircases across
                           // the detector): the tables take slabs of the volume that many lines
                           // of the densest view thick, so views with sparser lines take fewer;
                           // 0: JosephProjector::default_rows_per_block of the views
  void validate() const;   // std::invalid_argument naming the field
};

class JosephProjector {
 public:
  explicit JosephProjector(ProjectorOptions options = {});

  /// y = A x; y must be sized (views.size(), rows, cols) for the detector.
  void forward(ConstVolumeSpan x, const std::vector<ProjectionMatrix>& views, StackSpan y) const;
  /// x = A' y; x's layout is kept, its values overwritten.
  void back(ConstStackSpan y, const std::vector<ProjectionMatrix>& views, VolumeSpan x) const;
  // The same on owned storage (the spans' memory may be anyone's: a numpy array, a memory map).
  void forward(const Volume& x, const std::vector<ProjectionMatrix>& views, ProjectionStack& y) const {
    forward(ConstVolumeSpan(x), views, StackSpan(y));
  }
  void back(const ProjectionStack& y, const std::vector<ProjectionMatrix>& views, Volume& x) const {
    back(ConstStackSpan(y), views, VolumeSpan(x));
  }

  /// Detector lines per ray table for these views when ProjectorOptions::rows_per_block is 0:
  /// 8, or 24 where the views' rays typically cross the rows of their slices (the median view's
  /// central ray runs more than 0.2 voxel across rows per slice, as in spherical trajectories).
  static int default_rows_per_block(const std::vector<ProjectionMatrix>& views, const VolumeLayout& layout);

  /// The SIMD target chosen on this machine ("AVX3", "AVX2", ...) and its float lane count.
  static std::string simd_target();
  static int simd_lanes();
  /// Every target this binary has kernels for and this CPU runs, widest first.
  static std::vector<std::string> simd_targets();
  /// From now on, every projector in the process runs `target` (one of simd_targets()), or the
  /// widest again for "". For measuring what each target gives; not to be called while a
  /// projection runs. Throws std::invalid_argument naming the choices for any other name.
  static void use_simd_target(const std::string& target);
  int threads() const;

 private:
  // ProjectorOptions::rows_per_block, or its default for these views.
  int lines_per_table(const std::vector<ProjectionMatrix>& views, const VolumeLayout& layout) const;
  ProjectorOptions options_;
};

}  // namespace ctk

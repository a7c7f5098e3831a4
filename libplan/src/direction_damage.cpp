#include "ctk/plan/direction_damage.hpp"

#include <algorithm>
#include <cmath>
#include <functional>

#include "ctk/geom/trajectory.hpp"
#include "ctk/proj/joseph_projector.hpp"

namespace ctk {

namespace {

// The absorbers' bounding box (plus a voxel), as a volume of its own: projecting only it is what
// makes scoring hundreds of directions cheap.
Volume cropped_to_absorbers(const Volume& mask) {
  const auto& n = mask.layout.size;
  std::array<int, 3> lo{n[0], n[1], n[2]}, hi{-1, -1, -1};
  for (int k = 0; k < n[2]; ++k)
    for (int j = 0; j < n[1]; ++j)
      for (int i = 0; i < n[0]; ++i)
        if (mask.at(i, j, k) > 0) {
          const std::array<int, 3> p{i, j, k};
          for (int a = 0; a < 3; ++a) {
            lo[a] = std::min(lo[a], p[a]);
            hi[a] = std::max(hi[a], p[a]);
          }
        }
  VolumeLayout layout = mask.layout;
  for (int a = 0; a < 3; ++a) {
    lo[a] = std::max(0, lo[a] - 1);
    hi[a] = std::min(n[a] - 1, hi[a] + 1);
    layout.size[a] = hi[a] - lo[a] + 1;
    layout.origin_mm[a] += lo[a] * mask.layout.voxel_mm[a];
  }
  Volume out(layout);
  for (int k = 0; k < layout.size[2]; ++k)
    for (int j = 0; j < layout.size[1]; ++j)
      for (int i = 0; i < layout.size[0]; ++i) out.at(i, j, k) = mask.at(i + lo[0], j + lo[1], k + lo[2]);
  return out;
}

}  // namespace

ProjectionMatrix virtual_view(const Eigen::Vector3d& direction, const Intrinsics& K, double source_to_isocentre_mm) {
  return ProjectionMatrix::compose(
      K, make_rigid(rotation_looking_along(direction.normalized()), Eigen::Vector3d(0, 0, source_to_isocentre_mm)));
}

std::vector<DirectionDamage> direction_damage(const AbsorberSegmentation& segmentation,
                                              const std::vector<Eigen::Vector3d>& directions, const DamageGeometry& g) {
  std::vector<DirectionDamage> damage(directions.size());
  if (segmentation.voxels == 0 || directions.empty()) return damage;
  const Volume box = cropped_to_absorbers(segmentation.absorbers);
  // Frame the box from every direction: its farthest corner from the holder origin, magnified.
  double reach_mm = 0;
  for (int corner = 0; corner < 8; ++corner) {
    const Eigen::Vector3d c =
        box.layout.centre_of((corner & 1) ? box.layout.size[0] - 1 : 0, (corner & 2) ? box.layout.size[1] - 1 : 0,
                             (corner & 4) ? box.layout.size[2] - 1 : 0);
    reach_mm = std::max(reach_mm, c.norm() + box.layout.voxel_mm.maxCoeff());
  }
  const double magnification = g.source_to_detector_mm / (g.source_to_isocentre_mm - reach_mm);
  const double pitch = 2.0 * reach_mm * magnification / g.detector_pixels;
  const Detector detector{g.detector_pixels, g.detector_pixels, pitch, pitch};
  const Intrinsics K = Intrinsics::from_setup(g.source_to_detector_mm, detector, detector.centre_px());
  std::vector<ProjectionMatrix> views;
  views.reserve(directions.size());
  for (const Eigen::Vector3d& d : directions) views.push_back(virtual_view(d, K, g.source_to_isocentre_mm));

  ProjectionStack paths(static_cast<int>(views.size()), detector.rows, detector.cols);
  JosephProjector().forward(box, views, paths);
  const double min_path = 0.5 * box.layout.voxel_mm.minCoeff();
  for (std::size_t v = 0; v < views.size(); ++v) {
    const float* p = paths.view(static_cast<int>(v));
    std::vector<float> shadow;
    for (std::size_t i = 0; i < paths.pixels_per_view(); ++i)
      if (p[i] > min_path) shadow.push_back(p[i]);
    if (shadow.empty()) continue;
    const std::size_t top = std::max<std::size_t>(1, shadow.size() / 100);
    std::partial_sort(shadow.begin(), shadow.begin() + static_cast<std::ptrdiff_t>(top), shadow.end(), std::greater<>());
    double sum = 0;
    for (std::size_t i = 0; i < top; ++i) sum += shadow[i];
    damage[v] = {sum / static_cast<double>(top),
                 static_cast<double>(shadow.size()) / static_cast<double>(paths.pixels_per_view())};
  }
  return damage;
}

}  // namespace ctk

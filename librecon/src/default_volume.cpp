#include "ctk/recon/default_volume.hpp"

#include <algorithm>
#include <cmath>

#include "ctk/core/statistics.hpp"

namespace ctk {

double median_source_distance(const std::vector<ProjectionMatrix>& views) {
  std::vector<double> d;
  d.reserve(views.size());
  for (const auto& P : views) d.push_back(P.source_position().norm());
  return median(std::move(d));
}

VolumeLayout default_volume_layout(const ScanDescription& scan, const std::vector<ProjectionMatrix>& views, double voxel_mm,
                                   double coarsening) {
  const double sod = median_source_distance(views);
  const double demagnify = sod / scan.source_to_detector_mm;
  const double voxel = voxel_mm > 0 ? voxel_mm : scan.detector.pitch_u_mm * demagnify * coarsening;
  auto count = [&](double extent_mm) { return std::max(1, static_cast<int>(std::ceil(extent_mm / voxel))); };
  std::array<int, 3> size{};
  if (scan.holder) {
    size = {count(60.0), count(60.0), count(122.0)};  // the helix holder: a 60 x 60 x 122 mm box
  } else {
    const double across =
        std::max(scan.detector.cols * scan.detector.pitch_u_mm, scan.detector.rows * scan.detector.pitch_v_mm) * demagnify;
    size = {count(across), count(across), count(scan.detector.rows * scan.detector.pitch_v_mm * demagnify)};
  }
  return VolumeLayout::centred(size, Eigen::Vector3d::Constant(voxel));
}

}  // namespace ctk

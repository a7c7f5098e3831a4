#include "ctk/plan/absorber_segmentation.hpp"

#include <algorithm>
#include <cmath>
#include <vector>

namespace ctk {

namespace {

double percentile(std::vector<float> values, double q) {
  if (values.empty()) return 0;
  const auto k = static_cast<std::size_t>(std::clamp(q / 100.0, 0.0, 1.0) * static_cast<double>(values.size() - 1));
  std::nth_element(values.begin(), values.begin() + static_cast<std::ptrdiff_t>(k), values.end());
  return values[k];
}

}  // namespace

bool SampleRegion::contains(const Eigen::Vector3d& p) const {
  return p.head<2>().norm() <= radius_mm && std::abs(p.z()) <= half_height_mm;
}

AbsorberSegmentation segment_absorbers(const Volume& x, const SegmentationOptions& options) {
  AbsorberSegmentation s{Volume(x.layout), 0, 0, 0, 0, {}};
  const auto& n = x.layout.size;
  std::vector<std::size_t> inside;
  std::vector<float> values;
  for (int k = 0; k < n[2]; ++k)
    for (int j = 0; j < n[1]; ++j)
      for (int i = 0; i < n[0]; ++i)
        if (options.region.contains(x.layout.centre_of(i, j, k))) {
          inside.push_back(x.index(i, j, k));
          values.push_back(x.data[inside.back()]);
        }
  s.high_level = percentile(values, options.high_percentile);
  std::vector<float> material;
  for (float v : values)
    if (v > 0.1 * s.high_level) material.push_back(v);
  s.bulk_level = percentile(material, 50);
  if (!(s.high_level > 0) || !(s.bulk_level > 0)) {
    s.note = "the sample region is empty";
    return s;
  }
  if (s.high_level < options.min_contrast * s.bulk_level) {
    s.note = "no absorbers: the densest parts (" + std::to_string(s.high_level) + "/mm) are less than " +
             std::to_string(options.min_contrast) + " times the bulk (" + std::to_string(s.bulk_level) + "/mm)";
    return s;
  }
  s.threshold = 0.5 * (s.high_level + s.bulk_level);
  for (std::size_t i : inside)
    if (x.data[i] > s.threshold) {
      s.absorbers.data[i] = 1.0f;
      ++s.voxels;
    }
  return s;
}

}  // namespace ctk

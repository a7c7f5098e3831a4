#pragma once
// What the image-quality benchmarks share: a built-in phantom voxelised on a cube of voxels, the
// region scored (the cube's inscribed cylinder about +z) and the voxel at the truth's centre of
// mass that the line profiles run through; and a detector that sees the whole cube at
// magnification 2 (the detector twice as far from the source as the centre) with a pixel per voxel.
#include <algorithm>
#include <cmath>
#include <string>

#include "ctk/geom/detector.hpp"
#include "ctk/phantoms/builtin_phantoms.hpp"
#include "ctk/phantoms/render.hpp"
#include "ctk/plan/trajectory_quality.hpp"

namespace ctk::bench {

struct PhantomTruth {
  Phantom phantom;
  VolumeLayout layout;
  Volume truth;
  SampleRegion region;
  std::array<int, 3> through{};
  float peak = 0;  // the truth's largest value
};

inline PhantomTruth phantom_truth(const std::string& name, int size, double voxel_mm) {
  PhantomTruth t;
  t.phantom = builtin_phantom(name);
  t.layout = VolumeLayout::centred({size, size, size}, Eigen::Vector3d::Constant(voxel_mm));
  t.truth = voxelised(t.phantom, t.layout);
  t.region = {0.5 * size * voxel_mm, 0.5 * size * voxel_mm};
  t.through = centre_of_mass_voxel(t.truth, t.region);
  t.peak = *std::max_element(t.truth.data.begin(), t.truth.data.end());
  return t;
}

inline Detector detector_at_magnification_2(const PhantomTruth& t) {
  const int pixels = static_cast<int>(std::ceil(t.layout.size[0] * std::sqrt(3.0) * 1.05));
  return {pixels, pixels, 2 * t.layout.voxel_mm.x(), 2 * t.layout.voxel_mm.x()};
}

/// Every voxel scored as sample: these phantoms hold no absorber to leave out.
inline constexpr float kNoAbsorbers = 1e9f;

}  // namespace ctk::bench

#pragma once
// A float32 volume in the holder frame: voxel (i, j, k) has its centre at
// origin_mm + (i sx, j sy, k sz); stored x fastest, then y, then z.
#include <Eigen/Core>
#include <array>
#include <cstddef>
#include <string>

#include "ctk/core/float_buffer.hpp"

namespace ctk {

struct VolumeLayout {
  std::array<int, 3> size{0, 0, 0};
  Eigen::Vector3d voxel_mm{1, 1, 1};
  Eigen::Vector3d origin_mm{0, 0, 0};  // centre of voxel (0, 0, 0)

  /// A grid of `size` voxels centred on the holder origin.
  static VolumeLayout centred(const std::array<int, 3>& size, const Eigen::Vector3d& voxel_mm);
  std::size_t voxel_count() const {
    return static_cast<std::size_t>(size[0]) * static_cast<std::size_t>(size[1]) * static_cast<std::size_t>(size[2]);
  }
  std::array<std::ptrdiff_t, 3> strides() const { return {1, size[0], static_cast<std::ptrdiff_t>(size[0]) * size[1]}; }
  Eigen::Vector3d centre_of(int i, int j, int k) const;
  bool operator==(const VolumeLayout&) const = default;
};

/// A volume's voxels held elsewhere (a numpy array, a memory map): the layout and a pointer to
/// voxel_count() floats in the order of Volume. T is float or const float.
template <class T>
struct VolumeSpanOf {
  VolumeLayout layout;
  T* data = nullptr;
};
using VolumeSpan = VolumeSpanOf<float>;
using ConstVolumeSpan = VolumeSpanOf<const float>;

struct Volume {
  VolumeLayout layout;
  FloatBuffer data;

  explicit Volume(const VolumeLayout& l = {}) : layout(l), data(l.voxel_count(), 0.0f) {}
  float& at(int i, int j, int k) { return data[index(i, j, k)]; }
  float at(int i, int j, int k) const { return data[index(i, j, k)]; }
  operator VolumeSpan() { return {layout, data.data()}; }
  operator ConstVolumeSpan() const { return {layout, data.data()}; }
  std::size_t index(int i, int j, int k) const {
    return static_cast<std::size_t>(i) +
           static_cast<std::size_t>(layout.size[0]) *
               (static_cast<std::size_t>(j) + static_cast<std::size_t>(layout.size[1]) * static_cast<std::size_t>(k));
  }
};

/// One material's share of a volume made of several (the truth split by material: the shares add
/// up to the whole).
struct MaterialVolume {
  std::string material;  // empty for a share whose material is not named
  Volume volume;
};

}  // namespace ctk

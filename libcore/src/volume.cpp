#include "ctk/core/volume.hpp"

namespace ctk {

VolumeLayout VolumeLayout::centred(const std::array<int, 3>& size, const Eigen::Vector3d& voxel_mm) {
  VolumeLayout l;
  l.size = size;
  l.voxel_mm = voxel_mm;
  for (int a = 0; a < 3; ++a) l.origin_mm[a] = -0.5 * (size[static_cast<std::size_t>(a)] - 1) * voxel_mm[a];
  return l;
}

Eigen::Vector3d VolumeLayout::centre_of(int i, int j, int k) const {
  return origin_mm + Eigen::Vector3d(i, j, k).cwiseProduct(voxel_mm);
}

}  // namespace ctk

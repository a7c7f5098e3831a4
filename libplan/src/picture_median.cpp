#include "ctk/plan/picture_median.hpp"

#include <algorithm>
#include <array>

#include "ctk/core/parallel.hpp"

namespace ctk {

Volume median_3x3x3(const Volume& v) { return median_3x3x3(v, VoxelBox{{0, 0, 0}, v.layout.size}); }

Volume median_3x3x3(const Volume& v, const VoxelBox& box) {
  Volume out = v;
  const auto& n = v.layout.size;
  std::array<int, 3> lo{}, hi{};
  for (std::size_t a = 0; a < 3; ++a) {
    lo[a] = std::clamp(box.lo[a], 0, n[a]);
    hi[a] = std::clamp(box.hi[a], lo[a], n[a]);
  }
  const std::ptrdiff_t sy = n[0], sz = static_cast<std::ptrdiff_t>(n[0]) * n[1];
  parallel_for_dynamic(hi[2] - lo[2], [&](int dk) {
    const int k = lo[2] + dk;
    std::array<float, 27> near{};
    for (int j = lo[1]; j < hi[1]; ++j)
      for (int i = lo[0]; i < hi[0]; ++i) {
        const bool inside = i > 0 && j > 0 && k > 0 && i + 1 < n[0] && j + 1 < n[1] && k + 1 < n[2];
        std::size_t m = 0;
        if (inside) {  // the common case: the 27 neighbours by their offsets
          const float* c = &v.data[v.index(i, j, k)];
          for (std::ptrdiff_t dz = -sz; dz <= sz; dz += sz)
            for (std::ptrdiff_t dy = -sy; dy <= sy; dy += sy)
              for (std::ptrdiff_t dx = -1; dx <= 1; ++dx) near[m++] = c[dz + dy + dx];
        } else {
          for (int ok = -1; ok <= 1; ++ok)
            for (int oj = -1; oj <= 1; ++oj)
              for (int oi = -1; oi <= 1; ++oi)
                near[m++] =
                    v.at(std::clamp(i + oi, 0, n[0] - 1), std::clamp(j + oj, 0, n[1] - 1), std::clamp(k + ok, 0, n[2] - 1));
        }
        std::nth_element(near.begin(), near.begin() + 13, near.end());
        out.at(i, j, k) = near[13];
      }
  });
  return out;
}

}  // namespace ctk

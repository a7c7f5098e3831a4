#include "ctk/plan/picture_median.hpp"

#include <algorithm>
#include <array>

#include "ctk/core/parallel.hpp"

namespace ctk {

Volume median_3x3x3(const Volume& v) {
  Volume out(v.layout);
  const auto& n = v.layout.size;
  parallel_for_dynamic(n[2], [&](int k) {
    std::array<float, 27> near{};
    for (int j = 0; j < n[1]; ++j)
      for (int i = 0; i < n[0]; ++i) {
        std::size_t m = 0;
        for (int dk = -1; dk <= 1; ++dk)
          for (int dj = -1; dj <= 1; ++dj)
            for (int di = -1; di <= 1; ++di)
              near[m++] = v.at(std::clamp(i + di, 0, n[0] - 1), std::clamp(j + dj, 0, n[1] - 1), std::clamp(k + dk, 0, n[2] - 1));
        std::nth_element(near.begin(), near.begin() + 13, near.end());
        out.at(i, j, k) = near[13];
      }
  });
  return out;
}

}  // namespace ctk

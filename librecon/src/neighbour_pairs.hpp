#pragma once
// Sums and loops over the pairs of neighbouring voxels (along x, y and z, none across the volume's
// boundary), for the penalties on neighbour differences (regulariser.cpp, huber_penalty.cpp).
#include "ctk/core/volume.hpp"

namespace ctk::detail {

/// sum over pairs (i, i + e_a) of term(x[i + e_a] - x[i]), threaded, in double.
template <class Term>
double sum_over_neighbour_pairs(const Volume& x, const Term& term) {
  const auto& n = x.layout.size;
  const auto stride = x.layout.strides();
  double sum = 0;
#pragma omp parallel for reduction(+ : sum) schedule(static)
  for (int k = 0; k < n[2]; ++k)
    for (int j = 0; j < n[1]; ++j)
      for (int i = 0; i < n[0]; ++i) {
        const std::size_t at = x.index(i, j, k);
        const int index[3] = {i, j, k};
        for (int a = 0; a < 3; ++a)
          if (index[a] + 1 < n[a]) sum += term(double(x.data[at + static_cast<std::size_t>(stride[a])]) - x.data[at]);
      }
  return sum;
}

/// For every voxel, threaded: visit(at, differences, count), where differences[0 .. count) are
/// x[at] - x[neighbour] for each of its (up to six) neighbours inside the volume.
template <class Visit>
void for_each_voxel_with_its_neighbours(const Volume& x, const Visit& visit) {
  const auto& n = x.layout.size;
  const auto stride = x.layout.strides();
#pragma omp parallel for schedule(static)
  for (int k = 0; k < n[2]; ++k)
    for (int j = 0; j < n[1]; ++j)
      for (int i = 0; i < n[0]; ++i) {
        const std::size_t at = x.index(i, j, k);
        const int index[3] = {i, j, k};
        double differences[6];
        int count = 0;
        for (int a = 0; a < 3; ++a) {
          const std::size_t s = static_cast<std::size_t>(stride[a]);
          if (index[a] > 0) differences[count++] = double(x.data[at]) - x.data[at - s];
          if (index[a] + 1 < n[a]) differences[count++] = double(x.data[at]) - x.data[at + s];
        }
        visit(at, differences, count);
      }
}

}  // namespace ctk::detail

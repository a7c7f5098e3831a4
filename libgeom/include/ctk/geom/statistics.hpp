#pragma once
// Small robust statistics shared by the libraries: the median (for an even count, the upper of
// the two middle values; 0 when there are none).
#include <algorithm>
#include <cstddef>
#include <vector>

namespace ctk {

/// The median of `values`, reordering them.
template <class T>
T median_in_place(std::vector<T>& values) {
  if (values.empty()) return T{};
  const auto middle = values.begin() + static_cast<std::ptrdiff_t>(values.size() / 2);
  std::nth_element(values.begin(), middle, values.end());
  return *middle;
}

/// The median of `values` (a copy; pass std::move when they are not needed afterwards).
template <class T>
T median(std::vector<T> values) {
  return median_in_place(values);
}

}  // namespace ctk

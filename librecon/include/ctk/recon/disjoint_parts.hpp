#pragma once
// Two estimates of one quantity from disjoint parts of a scan (its halves in time, or the two
// pairs of opposite quarter turns) and an uncertainty that covers both. What differs between the
// parts (the object settling, the stage moving) is an error the scatter within the scan's views
// does not state: the spread of the two, |a - b| / 2 (the standard error of their mean), stands
// in for it when it is the larger.
#include <algorithm>
#include <cmath>
#include <nlohmann/json.hpp>

namespace ctk {

inline double covering_uncertainty(double first, double second, double within) {
  return std::max(within, std::abs(first - second) / 2);
}

/// {"first", "second", "within" (the scatter's own), "uncertainty" (covering both)}.
inline nlohmann::json disjoint_parts_json(double first, double second, double within) {
  return {{"first", first}, {"second", second}, {"within", within}, {"uncertainty", covering_uncertainty(first, second, within)}};
}

}  // namespace ctk

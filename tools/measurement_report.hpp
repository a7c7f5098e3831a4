#pragma once
// What reading the projections did to them, said on screen the same way by every command that
// reconstructs: masked pixels, views left out; none left is an error naming the geometry.
#include <filesystem>
#include <iostream>
#include <string>
#include <vector>

#include "ctk/core/error.hpp"
#include "ctk/measure/measurements.hpp"

namespace ctk::tools {

inline void report_masked_and_left_out(std::size_t masked_pixels, const std::vector<std::string>& left_out) {
  if (masked_pixels > 0)
    std::cout << "masked " << masked_pixels << " pixels that are not finite numbers (weight 0, their neighbours' mean)\n";
  for (const std::string& why : left_out) std::cerr << "warning: " << why << "\n";
}

inline void report_masked_and_left_out(const Measurements& m, const std::filesystem::path& geometry) {
  report_masked_and_left_out(m.masked_pixels, m.left_out);
  require_views_left(m, geometry.string());
}

}  // namespace ctk::tools

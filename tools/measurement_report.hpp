#pragma once
// What reading the projections did to them, said on screen the same way by every command that
// reconstructs: masked pixels, views left out; none left is an error naming the geometry.
#include <filesystem>
#include <iostream>

#include "ctk/geom/error.hpp"
#include "ctk/recon/measurements.hpp"

namespace ctk::tools {

inline void report_masked_and_left_out(const Measurements& m, const std::filesystem::path& geometry) {
  if (m.masked_pixels > 0)
    std::cout << "masked " << m.masked_pixels << " pixels that are not finite numbers (weight 0, their neighbours' mean)\n";
  for (const std::string& why : m.left_out) std::cerr << "warning: " << why << "\n";
  if (m.view_indices.empty() && !m.left_out.empty())
    throw InputError(geometry.string(), json_key("views"), "every ok view was left out: " + m.left_out.front());
}

}  // namespace ctk::tools

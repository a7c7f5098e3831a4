#pragma once
// A phantom: analytic primitives that add up, in the holder frame, and its JSON file
// (format "ctk-phantom/1", described in phantoms/README.md).
#include <filesystem>
#include <string>
#include <vector>

#include "ctk/phantoms/primitive.hpp"

namespace ctk {

struct Phantom {
  std::string name;
  std::vector<Primitive> primitives;

  /// Exact line integral (sum over primitives) along origin + t * direction, t >= 0; unit direction.
  double line_integral(const Eigen::Vector3d& origin, const Eigen::Vector3d& direction) const;
  /// Attenuation at a point (sum of the primitives containing it): the voxelised truth.
  double attenuation_at(const Eigen::Vector3d& point) const;
  /// Appends `other`'s primitives moved by T_this_other.
  void add(const Phantom& other, const Rigid& T_this_other = Rigid::Identity());
};

/// Reads a ctk-phantom/1 file; errors name the file and the key ("primitives[3].radius_mm").
/// Unknown keys are collected in `warnings` when given.
Phantom read_phantom(const std::filesystem::path& file, std::vector<std::string>* warnings = nullptr);
nlohmann::json phantom_to_json(const Phantom& phantom);
void write_phantom(const Phantom& phantom, const std::filesystem::path& file);  // atomically

}  // namespace ctk

#pragma once
// A trajectory given as beam directions (ctk-directions/1): a user's own, or one a search chose,
// acquired and scored beside the planned one by the trajectory comparison. The directions are
// tried in order until the trajectory has its views (a direction the robot cannot reach, or whose
// view cannot be calibrated, gives way to the next), so a list may hold spares after its views.
#include <Eigen/Core>
#include <filesystem>
#include <string>
#include <vector>

namespace ctk {

struct DirectionList {
  std::string name;                         // the trajectory's folder in the comparison
  std::vector<Eigen::Vector3d> directions;  // beam directions in the holder frame, unit length
};

/// InputError naming the file and the key for a list that is not ctk-directions/1, a name that is
/// not a folder name of lower-case letters, digits and '-', or a direction of zero length. (The
/// comparison refuses the names it gives its own trajectories.)
DirectionList read_direction_list(const std::filesystem::path& file);

void write_direction_list(const std::filesystem::path& file, const DirectionList& list);

}  // namespace ctk

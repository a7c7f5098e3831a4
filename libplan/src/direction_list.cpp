#include "ctk/plan/direction_list.hpp"

#include <algorithm>
#include <cctype>

#include "ctk/core/atomic_write.hpp"
#include "ctk/core/json_access.hpp"

namespace ctk {

DirectionList read_direction_list(const std::filesystem::path& file) {
  const nlohmann::json doc = read_json_file(file);
  const JsonNode root(doc, file.string(), "");
  if (root.at("format").string() != "ctk-directions/1") root.at("format").fail("expected \"ctk-directions/1\"");
  DirectionList list;
  const JsonNode name = root.at("name");
  list.name = name.string();
  const bool folder_name = !list.name.empty() && std::all_of(list.name.begin(), list.name.end(), [](unsigned char c) {
    return std::islower(c) != 0 || std::isdigit(c) != 0 || c == '-';
  });
  if (!folder_name) name.fail("expected a folder name of lower-case letters, digits and '-'");
  const JsonNode directions = root.at("directions");
  if (directions.size() == 0) directions.fail("expected at least one direction");
  for (std::size_t i = 0; i < directions.size(); ++i) {
    const Eigen::Vector3d d = directions.at(i).vector3();
    if (d.norm() < 1e-9) directions.at(i).fail("expected a direction, got a vector of zero length");
    list.directions.push_back(d.normalized());
  }
  return list;
}

void write_direction_list(const std::filesystem::path& file, const DirectionList& list) {
  nlohmann::json directions = nlohmann::json::array();
  for (const Eigen::Vector3d& d : list.directions) directions.push_back({d.x(), d.y(), d.z()});
  const nlohmann::json doc = {{"format", "ctk-directions/1"}, {"name", list.name}, {"directions", directions}};
  write_text_atomically(file, doc.dump(1) + "\n");
}

}  // namespace ctk

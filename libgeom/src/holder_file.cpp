#include "ctk/geom/holder_file.hpp"

#include <cmath>

#include "ctk/core/error.hpp"

namespace ctk {

namespace {

const char* kFormat = "ctk-holder/1";

Helix helix_from_json(const JsonNode& node) {
  node.warn_unknown_keys({"radius_mm", "rho_rad_per_mm", "pitch_mm", "phase_rad"});
  Helix helix;
  helix.radius_mm = node.at("radius_mm").length_mm();
  // The turn per millimetre, or the rise per turn a drawing gives (rho = 2 pi / pitch); not both.
  if (node.has("rho_rad_per_mm") == node.has("pitch_mm"))
    node.fail("expected exactly one of rho_rad_per_mm (turn per mm along the axis) and pitch_mm (rise per turn)");
  if (node.has("pitch_mm")) {
    const JsonNode pitch = node.at("pitch_mm");
    const double p = pitch.number();
    if (!(std::abs(p) >= JsonNode::kShortestLengthMm && std::abs(p) <= JsonNode::kLongestLengthMm))
      pitch.fail("expected a rise per turn of 1e-6 to 1e6 mm (negative: a left-handed helix)");
    helix.rho_rad_per_mm = 2 * M_PI / p;
  } else {
    helix.rho_rad_per_mm = node.at("rho_rad_per_mm").number();
  }
  helix.phase_rad = node.at("phase_rad").number();
  return helix;
}

std::vector<Eigen::Vector3d> spheres_on_helix(const JsonNode& node, const Helix& helix) {
  node.warn_unknown_keys({"count", "tau_mm"});
  const JsonNode count = node.at("count");
  const int n = count.integer();
  if (n < 1 || n > 100000) count.fail("expected 1 to 100000 spheres");
  const std::vector<double> tau = node.at("tau_mm").numbers(2);
  if (n > 1 && !(tau[0] < tau[1])) node.at("tau_mm").fail("expected [first, last] along the axis, first below last");
  return Holder::on_helix(helix, 1.0, n, tau[0], tau[1]).spheres_mm;
}

// A mesh named relative to the file that names it (a holder or a scan file) is found beside it.
HolderBody body_from_json(const JsonNode& node) {
  node.warn_unknown_keys({"mesh", "unit_mm", "material"});
  HolderBody body;
  body.mesh = node.at("mesh").string();
  if (body.mesh.empty()) node.at("mesh").fail("expected the body's STL file");
  if (body.mesh.is_relative() && !node.file().empty()) body.mesh = std::filesystem::path(node.file()).parent_path() / body.mesh;
  if (node.has("unit_mm")) {
    const JsonNode unit = node.at("unit_mm");
    body.unit_mm = unit.positive_number();
    if (!(body.unit_mm >= 1e-6 && body.unit_mm <= 1e6)) unit.fail("expected 1e-6 to 1e6 mm per file unit");
  }
  if (node.has("material")) body.material = node.at("material").string();
  return body;
}

}  // namespace

Holder holder_from_json(const JsonNode& node) {
  node.warn_unknown_keys(
      {"format", "name", "measurement", "helix", "sphere_diameter_mm", "spheres_mm", "spheres_on_helix", "wall", "body"});
  Holder h;
  h.helix = helix_from_json(node.at("helix"));
  h.sphere_diameter_mm = node.at("sphere_diameter_mm").length_mm();
  if (node.has("spheres_mm") == node.has("spheres_on_helix"))
    node.fail("expected exactly one of spheres_mm (the centres listed) and spheres_on_helix (count and tau range)");
  if (node.has("spheres_on_helix")) {
    h.spheres_mm = spheres_on_helix(node.at("spheres_on_helix"), h.helix);
  } else {
    const JsonNode spheres = node.at("spheres_mm");
    for (std::size_t i = 0; i < spheres.size(); ++i) h.spheres_mm.push_back(spheres.at(i).position_mm());
    if (h.spheres_mm.empty()) spheres.fail("expected at least one sphere centre");
  }
  if (node.has("wall")) {
    const JsonNode wall = node.at("wall");
    wall.warn_unknown_keys({"inner_radius_mm", "outer_radius_mm", "ends_mm"});
    h.wall = HolderWall{wall.at("inner_radius_mm").length_mm(), wall.at("outer_radius_mm").length_mm(), std::nullopt};
    if (!(h.wall->outer_radius_mm > h.wall->inner_radius_mm))
      wall.at("outer_radius_mm").fail("expected more than inner_radius_mm");
    if (wall.has("ends_mm")) {
      const JsonNode ends = wall.at("ends_mm");
      if (ends.size() != 2) ends.fail("expected the tube's two ends along the holder axis, [lower, upper] in mm");
      h.wall->ends_mm = Eigen::Vector2d(ends.at(0).number(), ends.at(1).number());
      if (!(h.wall->ends_mm->x() < h.wall->ends_mm->y())) ends.fail("expected the lower end first");
      if (h.wall->ends_mm->x() > h.tau_min() || h.wall->ends_mm->y() < h.tau_max())
        ends.fail("expected ends beyond the spheres the tube carries (" + std::to_string(h.tau_min()) + " to " +
                  std::to_string(h.tau_max()) + " mm)");
    }
  }
  if (node.has("body")) h.body = body_from_json(node.at("body"));
  return h;
}

nlohmann::json holder_to_json(const Holder& h) {
  nlohmann::json spheres = nlohmann::json::array();
  for (const auto& s : h.spheres_mm) spheres.push_back({s.x(), s.y(), s.z()});
  nlohmann::json j = {
      {"helix", {{"radius_mm", h.helix.radius_mm}, {"rho_rad_per_mm", h.helix.rho_rad_per_mm}, {"phase_rad", h.helix.phase_rad}}},
      {"sphere_diameter_mm", h.sphere_diameter_mm},
      {"spheres_mm", spheres}};
  if (h.wall) {
    j["wall"] = {{"inner_radius_mm", h.wall->inner_radius_mm}, {"outer_radius_mm", h.wall->outer_radius_mm}};
    if (h.wall->ends_mm) j["wall"]["ends_mm"] = {h.wall->ends_mm->x(), h.wall->ends_mm->y()};
  }
  if (h.body)
    j["body"] = {{"mesh", std::filesystem::absolute(h.body->mesh).lexically_normal().string()},
                 {"unit_mm", h.body->unit_mm},
                 {"material", h.body->material}};
  return j;
}

Holder read_holder_file(const std::filesystem::path& file) {
  const nlohmann::json root = read_json_file(file);
  const JsonNode top(root, file.string(), "");
  if (!root.is_object()) top.fail("expected a JSON object");
  const std::string format = top.at("format").string();
  if (format != kFormat) top.at("format").fail("expected \"" + std::string(kFormat) + "\", got \"" + format + "\"");
  return holder_from_json(top);
}

std::vector<std::string> builtin_holder_names() { return {"reference", "thesis-first"}; }

Holder thesis_first_holder() {
  const double outer = 17.5 + 2.0;
  const Helix helix{outer, 4 * M_PI / 48.0, 0.0};
  Holder holder = Holder::on_helix(helix, 0.678, 50, -24.0, 24.0);
  holder.wall = HolderWall{17.5, outer, Eigen::Vector2d(-28.0, 28.0)};
  return holder;
}

Holder holder_named(const std::string& name) {
  if (name == "reference") return reference_helix_holder();
  if (name == "thesis-first") return thesis_first_holder();
  if (std::filesystem::path(name).extension() == ".json") return read_holder_file(name);
  std::string known;
  for (const std::string& n : builtin_holder_names()) known += (known.empty() ? "" : ", ") + n;
  throw InputError(name, "", "is neither a built-in holder (" + known + ") nor a ctk-holder/1 file (.json)");
}

}  // namespace ctk

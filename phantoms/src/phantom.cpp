#include "ctk/phantoms/phantom.hpp"

#include <cmath>

#include "ctk/core/atomic_write.hpp"
#include "ctk/core/json_access.hpp"
#include "ctk/core/provenance.hpp"
#include "ctk/phantoms/material_attenuation.hpp"

namespace ctk {

double Phantom::line_integral(const Eigen::Vector3d& origin, const Eigen::Vector3d& direction) const {
  double sum = 0;
  for (const auto& p : primitives) sum += p.line_integral(origin, direction);
  return sum;
}

double Phantom::attenuation_at(const Eigen::Vector3d& point) const {
  double sum = 0;
  for (const auto& p : primitives)
    if (p.contains(point)) sum += p.attenuation_per_mm;
  return sum;
}

void Phantom::add(const Phantom& other, const Rigid& T_this_other) {
  for (Primitive p : other.primitives) {
    p.pose = T_this_other * p.pose;
    primitives.push_back(std::move(p));
  }
}

namespace {

constexpr double kDegree = M_PI / 180.0;

Primitive shape_from_json(const JsonNode& node) {
  const std::string type = node.at("type").string();
  const Eigen::Vector3d centre = node.at("center_mm").vector3();
  const double mu = node.at("attenuation_per_mm").number();
  Eigen::Matrix3d R = Eigen::Matrix3d::Identity();
  if (auto r = node.find("rotation_vector_deg")) R = rotation_from_vector(r->vector3() * kDegree);
  std::string label;
  if (auto l = node.find("label")) label = l->string();
  if (type == "sphere") {
    node.warn_unknown_keys({"type", "center_mm", "attenuation_per_mm", "label", "material", "radius_mm"});
    return Primitive::sphere(centre, node.at("radius_mm").positive_number(), mu, label);
  }
  auto positive3 = [&](const char* key) {
    const JsonNode n = node.at(key);
    Eigen::Vector3d v = n.vector3();
    if ((v.array() <= 0).any()) n.fail("expected three positive numbers");
    return v;
  };
  if (type == "ellipsoid") {
    node.warn_unknown_keys({"type", "center_mm", "attenuation_per_mm", "label", "material", "rotation_vector_deg", "radii_mm"});
    return Primitive::ellipsoid(centre, positive3("radii_mm"), R, mu, label);
  }
  if (type == "cylinder") {
    node.warn_unknown_keys(
        {"type", "center_mm", "attenuation_per_mm", "label", "material", "rotation_vector_deg", "radius_mm", "height_mm"});
    return Primitive::cylinder(centre, node.at("radius_mm").positive_number(), node.at("height_mm").positive_number(), R, mu,
                               label);
  }
  if (type == "mesh") {
    // A closed triangle mesh from an STL file beside the phantom file (binary or ASCII), its
    // coordinates in `scale_mm` millimetres (1: the file is in mm), its origin at center_mm.
    node.warn_unknown_keys(
        {"type", "center_mm", "attenuation_per_mm", "label", "material", "rotation_vector_deg", "file", "scale_mm"});
    const std::string name = node.at("file").string();
    const double scale = node.has("scale_mm") ? node.at("scale_mm").positive_number() : 1.0;
    const std::filesystem::path folder = std::filesystem::path(node.file()).parent_path();
    const std::filesystem::path stl = std::filesystem::path(name).is_absolute() ? std::filesystem::path(name) : folder / name;
    Primitive p =
        Primitive::from_mesh(std::make_shared<const TriangleMesh>(TriangleMesh::read_stl(stl, scale)), centre, R, mu, label);
    p.mesh_file = name;
    p.mesh_scale_mm = scale;
    return p;
  }
  if (type == "box") {
    node.warn_unknown_keys({"type", "center_mm", "attenuation_per_mm", "label", "material", "rotation_vector_deg", "size_mm"});
    return Primitive::box(centre, positive3("size_mm"), R, mu, label);
  }
  node.at("type").fail("expected \"sphere\", \"ellipsoid\", \"cylinder\", \"box\" or \"mesh\", got \"" + type + "\"");
}

Primitive primitive_from_json(const JsonNode& node) {
  Primitive p = shape_from_json(node);
  if (auto m = node.find("material")) {
    p.material = m->string();
    if (!is_known_material(p.material)) {
      std::string names;
      for (const auto& n : known_materials()) names += (names.empty() ? "" : ", ") + n;
      m->fail("unknown material \"" + p.material + "\" (known: " + names + ")");
    }
  }
  return p;
}

nlohmann::json primitive_to_json(const Primitive& p) {
  nlohmann::json j;
  j["type"] = to_string(p.shape);
  if (!p.label.empty()) j["label"] = p.label;
  const Eigen::Vector3d c = p.pose.translation();
  j["center_mm"] = {c.x(), c.y(), c.z()};
  const Eigen::Vector3d h = p.half_size_mm;
  switch (p.shape) {
    case Shape::sphere:
      j["radius_mm"] = h.x();
      break;
    case Shape::ellipsoid:
      j["radii_mm"] = {h.x(), h.y(), h.z()};
      break;
    case Shape::cylinder:
      j["radius_mm"] = h.x();
      j["height_mm"] = 2 * h.z();
      break;
    case Shape::box:
      j["size_mm"] = {2 * h.x(), 2 * h.y(), 2 * h.z()};
      break;
    case Shape::mesh:
      j["file"] = p.mesh_file;
      j["scale_mm"] = p.mesh_scale_mm;
      break;
  }
  if (p.shape != Shape::sphere) {
    const Eigen::Vector3d r = rotation_vector(p.pose.linear()) / kDegree;
    if (r.norm() > 0) j["rotation_vector_deg"] = {r.x(), r.y(), r.z()};
  }
  j["attenuation_per_mm"] = p.attenuation_per_mm;
  if (!p.material.empty()) j["material"] = p.material;
  return j;
}

}  // namespace

Phantom read_phantom(const std::filesystem::path& file, std::vector<std::string>* warnings) {
  const nlohmann::json json = read_json_file(file);
  const JsonNode root(json, file.string(), "", warnings);
  if (root.at("format").string() != "ctk-phantom/1") root.at("format").fail("expected \"ctk-phantom/1\"");
  root.warn_unknown_keys({"format", "provenance", "name", "units", "primitives"});
  Phantom phantom;
  phantom.name = root.find("name") ? root.at("name").string() : file.stem().string();
  const JsonNode list = root.at("primitives");
  for (std::size_t i = 0; i < list.size(); ++i) phantom.primitives.push_back(primitive_from_json(list.at(i)));
  if (phantom.primitives.empty()) list.fail("a phantom needs at least one primitive");
  return phantom;
}

nlohmann::json phantom_to_json(const Phantom& phantom) {
  nlohmann::json j;
  j["format"] = "ctk-phantom/1";
  j["provenance"] = provenance();
  j["name"] = phantom.name;
  j["units"] = "lengths in mm (holder frame), attenuation in 1/mm, rotation vectors in degrees";
  j["primitives"] = nlohmann::json::array();
  for (const auto& p : phantom.primitives) j["primitives"].push_back(primitive_to_json(p));
  return j;
}

void write_phantom(const Phantom& phantom, const std::filesystem::path& file) {
  write_text_atomically(file, phantom_to_json(phantom).dump(2) + "\n");
}

}  // namespace ctk

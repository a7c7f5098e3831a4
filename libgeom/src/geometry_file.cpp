#include "ctk/geom/geometry_file.hpp"

#include "ctk/core/atomic_write.hpp"
#include "ctk/core/error.hpp"
#include "ctk/core/json_access.hpp"
#include "ctk/core/provenance.hpp"

namespace ctk {

namespace {
const char* kFormat = "ctk-geometry/1";
}

const char* to_string(ViewStatus status) {
  switch (status) {
    case ViewStatus::ok:
      return "ok";
    case ViewStatus::rejected:
      return "rejected";
    case ViewStatus::skipped:
      return "skipped";
  }
  return "?";
}

std::vector<int> Geometry::ok_views() const {
  std::vector<int> out;
  for (std::size_t i = 0; i < views.size(); ++i)
    if (views[i].status == ViewStatus::ok) out.push_back(static_cast<int>(i));
  return out;
}

std::string Geometry::description() const {
  const std::string what = origin.empty() ? std::string("matrices of unstated origin") : origin;
  return file.empty() ? what : what + " (" + file.string() + ")";
}

std::string Geometry::source() const { return file.empty() ? std::string("geometry") : file.string(); }

Geometry read_geometry(const std::filesystem::path& file) { return geometry_from_json(read_json_file(file), file); }

Geometry geometry_from_json(const nlohmann::json& root, const std::filesystem::path& file) {
  std::vector<std::string> warnings;  // geometry files are machine-written; unknown keys are not reported
  const JsonNode top(root, file.string(), "", &warnings);
  const std::string format = top.at("format").string();
  if (format != kFormat) top.at("format").fail("expected \"" + std::string(kFormat) + "\", got \"" + format + "\"");
  Geometry g;
  g.file = file;
  if (auto origin = top.find("origin")) g.origin = origin->string();
  const JsonNode det = top.at("detector");
  g.detector.cols = det.at("cols").integer();
  g.detector.rows = det.at("rows").integer();
  const auto pitch = det.at("pixel_pitch_mm").numbers(2);
  if (g.detector.cols <= 0 || g.detector.rows <= 0) det.fail("cols and rows must be positive");
  if (!(pitch[0] > 0 && pitch[1] > 0)) det.at("pixel_pitch_mm").fail("expected two positive pitches");
  g.detector.pitch_u_mm = pitch[0];
  g.detector.pitch_v_mm = pitch[1];
  const JsonNode views = top.at("views");
  for (std::size_t i = 0; i < views.size(); ++i) {
    const JsonNode v = views.at(i);
    GeometryView view;
    view.index = v.at("index").integer();
    if (auto p = v.find("projection")) view.projection = p->string();
    const std::string status = v.at("status").string();
    if (status == "ok")
      view.status = ViewStatus::ok;
    else if (status == "rejected")
      view.status = ViewStatus::rejected;
    else if (status == "skipped")
      view.status = ViewStatus::skipped;
    else
      v.at("status").fail("expected \"ok\", \"rejected\" or \"skipped\", got \"" + status + "\"");
    if (auto r = v.find("reason")) view.reason = r->string();
    if (auto P = v.find("P")) {
      const auto values = P->numbers(12);
      std::array<double, 12> a{};
      std::copy(values.begin(), values.end(), a.begin());
      try {
        view.P = ProjectionMatrix::from_row_major(a);
      } catch (const std::invalid_argument& e) {
        P->fail(e.what());
      }
    } else if (view.status == ViewStatus::ok) {
      throw InputError(file.string(), json_key(v.path() + ".P"), "missing (required for a view with status \"ok\")");
    }
    if (auto r = v.find("rms_px")) view.rms_px = r->number();
    if (auto s = v.find("spheres_used")) view.spheres_used = s->integer();
    g.views.push_back(std::move(view));
  }
  return g;
}

nlohmann::json geometry_to_json(const Geometry& g) {
  using nlohmann::json;
  json views = json::array();
  for (const auto& v : g.views) {
    json jv = {{"index", v.index}, {"projection", v.projection}, {"status", to_string(v.status)}, {"reason", v.reason}};
    if (v.P) jv["P"] = v.P->row_major();
    if (v.rms_px) jv["rms_px"] = *v.rms_px;
    if (v.spheres_used) jv["spheres_used"] = *v.spheres_used;
    views.push_back(std::move(jv));
  }
  json j = {{"format", kFormat},
            {"provenance", provenance()},
            {"detector",
             {{"cols", g.detector.cols},
              {"rows", g.detector.rows},
              {"pixel_pitch_mm", {g.detector.pitch_u_mm, g.detector.pitch_v_mm}}}},
            {"views", views}};
  if (!g.origin.empty()) j["origin"] = g.origin;
  return j;
}

void write_geometry(const Geometry& g, const std::filesystem::path& file) {
  write_text_atomically(file, geometry_to_json(g).dump(1) + "\n");
}

}  // namespace ctk

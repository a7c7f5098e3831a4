#pragma once
// Calibrated (or nominal) per-view geometry, format "ctk-geometry/1" (scan-format.md).
#include <filesystem>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "ctk/geom/detector.hpp"
#include "ctk/geom/projection_matrix.hpp"

namespace ctk {

enum class ViewStatus { ok, rejected, skipped };
const char* to_string(ViewStatus status);

struct GeometryView {
  int index = 0;
  std::string projection;  // file name as in the scan
  ViewStatus status = ViewStatus::ok;
  std::string reason;                 // why, when not ok
  std::optional<ProjectionMatrix> P;  // present for every ok view
  std::optional<double> rms_px;
  std::optional<int> spheres_used;
};

struct Geometry {
  Detector detector;
  std::vector<GeometryView> views;
  std::filesystem::path file;  // what read_geometry read it from; empty for one made in memory
  /// Where the matrices come from (optional key `origin`, an extension of ctk-geometry/1):
  /// "nominal" (the setup's prediction or numbers imported), "calibrated" (fitted to the helix
  /// spheres), "refined" (the markerless loop); empty when a file does not say.
  std::string origin;
  /// "refined (run/refine.geometry.json)": what a run names the geometry it uses by.
  std::string description() const;

  std::vector<int> ok_views() const;  // indices into views
  /// The file for error messages: `file`, or "geometry" for one made in memory.
  std::string source() const;
};

/// Throws InputError naming file and key; an "ok" view must carry P.
Geometry read_geometry(const std::filesystem::path& file);
/// The same checks on a document already in memory; `file` names it in errors.
Geometry geometry_from_json(const nlohmann::json& root, const std::filesystem::path& file);
nlohmann::json geometry_to_json(const Geometry& geometry);
void write_geometry(const Geometry& geometry, const std::filesystem::path& file);

}  // namespace ctk

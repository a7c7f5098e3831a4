#include "ctk/geom/scan.hpp"

#include <cmath>
#include <cstdio>

#include "ctk/core/atomic_write.hpp"
#include "ctk/core/provenance.hpp"
#include "ctk/geom/detector_binning.hpp"
#include "ctk/geom/holder_file.hpp"

namespace ctk {

namespace fs = std::filesystem;

namespace {

const char* kFormat = "ctk-scan/1";

// Exactly one conversion, %d with an optional zero flag and width, and no other '%'. Scanned by
// hand: std::regex recurses per character and overflows the stack on a pattern of some 10^4.
bool is_printf_pattern(const std::string& pattern) {
  const std::size_t percent = pattern.find('%');
  if (percent == std::string::npos || pattern.find('%', percent + 1) != std::string::npos) return false;
  std::size_t i = percent + 1;
  if (i < pattern.size() && pattern[i] == '0') ++i;
  while (i < pattern.size() && pattern[i] >= '0' && pattern[i] <= '9') ++i;
  return i < pattern.size() && pattern[i] == 'd';
}

void require_readable(const ScanDescription& scan, const JsonNode& node, const std::string& name) {
  const fs::path path = scan.resolve(name);
  std::error_code ec;
  if (!fs::is_regular_file(path, ec)) node.fail("file '" + path.string() + "' does not exist or is not a file");
  if (FILE* f = std::fopen(path.c_str(), "rb")) {
    std::fclose(f);
  } else {
    node.fail("file '" + path.string() + "' cannot be read");
  }
}

// One file name or a non-empty list of them (frames to average), each readable.
std::vector<std::string> read_frame_names(const ScanDescription& scan, const JsonNode& node) {
  std::vector<std::string> names;
  if (node.raw().is_array()) {
    if (node.size() == 0) node.fail("expected a file name or a non-empty list of file names");
    for (std::size_t i = 0; i < node.size(); ++i) {
      names.push_back(node.at(i).string());
      require_readable(scan, node.at(i), names.back());
    }
  } else {
    names.push_back(node.string());
    require_readable(scan, node, names.back());
  }
  return names;
}

nlohmann::json frame_names_to_json(const std::vector<std::string>& names) {
  if (names.size() == 1) return names.front();
  return names;
}

Detector read_detector(const JsonNode& node, Eigen::Vector2d* principal_point) {
  node.warn_unknown_keys({"cols", "rows", "pixel_pitch_mm", "principal_point_px", "radial_distortion", "binning"});
  Detector d;
  d.cols = node.at("cols").integer();
  d.rows = node.at("rows").integer();
  if (d.cols <= 0) node.at("cols").fail("expected a positive integer");
  if (d.rows <= 0) node.at("rows").fail("expected a positive integer");
  const JsonNode pitches = node.at("pixel_pitch_mm");
  if (pitches.size() != 2) pitches.fail("expected two pitches (columns, rows), got " + std::to_string(pitches.size()));
  const double pitch[2] = {pitches.at(0).length_mm(), pitches.at(1).length_mm()};
  d.pitch_u_mm = pitch[0];
  d.pitch_v_mm = pitch[1];
  if (principal_point) {
    const auto pp = node.at("principal_point_px").numbers(2);
    // Off the detector is possible (an offset detector); a kilometre off is a damaged number.
    if (std::abs(pp[0] * d.pitch_u_mm) > JsonNode::kLongestLengthMm ||
        std::abs(pp[1] * d.pitch_v_mm) > JsonNode::kLongestLengthMm)
      node.at("principal_point_px").fail("expected a point within 1e+06 mm of the detector's first pixel");
    *principal_point = {pp[0], pp[1]};
  }
  return d;
}

ProjectionSet read_projections(const JsonNode& node, const ScanDescription& scan) {
  node.warn_unknown_keys({"files", "count", "kind", "flat", "dark"});
  ProjectionSet p;
  const JsonNode files = node.at("files");
  if (files.raw().is_string()) {
    p.files_pattern = files.string();
    if (!is_printf_pattern(p.files_pattern))
      files.fail("expected a printf pattern with one integer conversion such as proj_%04d.tif, got '" + p.files_pattern + "'");
    p.count = node.at("count").integer();
  } else if (files.raw().is_array()) {
    for (std::size_t i = 0; i < files.size(); ++i) p.file_names.push_back(files.at(i).string());
    p.count = static_cast<int>(p.file_names.size());
    if (auto count = node.find("count"); count && count->integer() != p.count)
      count->fail("is " + std::to_string(count->integer()) + " but 'files' lists " + std::to_string(p.count) + " names");
  } else {
    files.fail("expected a printf pattern (string) or a list of file names");
  }
  if (p.count <= 0) node.at("count").fail("expected a positive number of projections");
  const std::string kind = node.at("kind").string();
  if (kind == "counts") {
    p.kind = ProjectionKind::counts;
    p.flat = read_frame_names(scan, node.at("flat"));
    p.dark = read_frame_names(scan, node.at("dark"));
  } else if (kind == "line_integrals") {
    p.kind = ProjectionKind::line_integrals;
  } else {
    node.at("kind").fail("expected \"counts\" or \"line_integrals\", got \"" + kind + "\"");
  }
  return p;
}

}  // namespace

std::string ProjectionSet::file_name(int view) const {
  if (!file_names.empty()) return file_names.at(static_cast<std::size_t>(view));
  char buffer[1024];
  std::snprintf(buffer, sizeof buffer, files_pattern.c_str(), view);
  return buffer;
}

fs::path ScanDescription::resolve(const std::string& name) const {
  const fs::path p(name);
  return p.is_absolute() ? p : folder / p;
}

ProjectionCensus take_projection_census(const ScanDescription& scan) {
  ProjectionCensus census;
  for (int v = 0; v < scan.projections.count; ++v) {
    const fs::path file = scan.projection_path(v).lexically_normal();
    std::error_code ec;
    if (fs::exists(file, ec)) {
      if (census.first_present.empty()) census.first_present = file;
    } else if (census.missing++ == 0) {
      census.first_missing = file;
    }
  }
  return census;
}

ProjectionCensus require_projection_files(const ScanDescription& scan, const std::string& file, const std::string& key) {
  ProjectionCensus census = take_projection_census(scan);
  const int count = scan.projections.count;
  if (census.first_present.empty())
    throw InputError(file, key,
                     "none of the " + std::to_string(count) + " projection files exists (the first would be " +
                         census.first_missing.string() + ")");
  if (census.missing > count / 2)
    throw InputError(file, key,
                     std::to_string(census.missing) + " of the " + std::to_string(count) +
                         " projection files do not exist (the first is " + census.first_missing.string() +
                         "): is the count or the file pattern wrong?");
  return census;
}

ScanDescription relocated_scan(const ScanDescription& scan, const fs::path& file) {
  ScanDescription out = scan;
  out.folder = file.has_parent_path() ? file.parent_path() : fs::path(".");
  const fs::path to = fs::absolute(out.folder).lexically_normal();
  auto move = [&](std::string& name) {
    if (name.empty() || fs::path(name).is_absolute()) return;
    name = fs::absolute(scan.resolve(name)).lexically_normal().lexically_proximate(to).string();
  };
  move(out.projections.files_pattern);
  for (auto* names : {&out.projections.file_names, &out.projections.flat, &out.projections.dark})
    for (std::string& n : *names) move(n);
  if (out.panda) move(out.panda->joints_csv);
  if (out.matrices) move(out.matrices->file);
  if (out.holder_file) move(out.holder_file->name);
  return out;
}

void state_matrices_intrinsics(ScanDescription& scan) {
  if (!scan.matrices) return;
  for (const GeometryView& v : scan.matrices->geometry.views) {
    if (!v.P) continue;
    const auto first = v.P->decompose();
    scan.source_to_detector_mm = std::abs(first.intrinsics.fu_px) * scan.detector.pitch_u_mm;
    scan.principal_point_px = {first.intrinsics.u0_px, first.intrinsics.v0_px};
    return;
  }
}

void bin_scan(ScanDescription& scan, int factor) {
  if (factor == 1) return;
  const Detector before = scan.detector;
  if (scan.binning == 1) scan.stored_detector = before;
  scan.detector = binned_detector(before, factor);
  scan.principal_point_px = binned_pixel(scan.principal_point_px, factor);
  if (scan.distortion) scan.distortion = binned_distortion(*scan.distortion, factor);
  // A geometry already made for the binned detector (a refined scan's matrices) stays as it is.
  if (scan.matrices && scan.matrices->geometry.detector.cols == before.cols &&
      scan.matrices->geometry.detector.rows == before.rows)
    scan.matrices->geometry = binned_geometry(scan.matrices->geometry, factor);
  scan.binning *= factor;
}

Geometry geometry_for_scan(const ScanDescription& scan, const Geometry& geometry) {
  if (scan.binning > 1 && geometry.detector.cols == scan.stored_detector.cols &&
      geometry.detector.rows == scan.stored_detector.rows)
    return binned_geometry(geometry, scan.binning);
  return geometry;
}

ScanDescription read_scan(const fs::path& file) { return scan_from_json(read_json_file(file), file); }

// NOLINTNEXTLINE(readability-function-size): one key per statement, each refused by its name
ScanDescription scan_from_json(const nlohmann::json& root, const fs::path& file) {
  ScanDescription scan;
  scan.folder = file.has_parent_path() ? file.parent_path() : fs::path(".");
  const JsonNode top(root, file.string(), "", &scan.warnings);
  if (!root.is_object()) top.fail("expected a JSON object");
  top.warn_unknown_keys({"format", "provenance", "detector", "source_to_detector_mm", "projections", "pose_source", "holder",
                         "source_drift_mm_per_100_views", "written_by"});
  const std::string format = top.at("format").string();
  if (format != kFormat) top.at("format").fail("expected \"" + std::string(kFormat) + "\", got \"" + format + "\"");

  scan.detector = read_detector(top.at("detector"), &scan.principal_point_px);
  if (auto rd = top.at("detector").find("radial_distortion")) {
    rd->warn_unknown_keys({"k1_per_px2", "center_px"});
    const auto c = rd->at("center_px").numbers(2);
    scan.distortion = RadialDistortion{rd->at("k1_per_px2").number(), {c[0], c[1]}};
  }
  scan.source_to_detector_mm = top.at("source_to_detector_mm").length_mm();
  if (auto drift = top.find("source_drift_mm_per_100_views")) {
    const auto d = drift->numbers(2);
    scan.source_drift_mm_per_100_views = {d[0], d[1]};
  }
  scan.projections = read_projections(top.at("projections"), scan);
  if (auto by = top.find("written_by")) {
    by->warn_unknown_keys({"run"});
    scan.written_by_run = by->at("run").string();
  }

  const JsonNode pose = top.at("pose_source");
  const std::string kind = pose.at("kind").string();
  if (kind == "panda") {
    pose.warn_unknown_keys({"kind", "joints_csv", "T_camera_base", "T_flange_holder", "joint_offsets_rad"});
    PandaPoseSource panda;
    panda.joints_csv = pose.at("joints_csv").string();
    require_readable(scan, pose.at("joints_csv"), panda.joints_csv);
    panda.T_camera_base = rigid_from_json(pose.at("T_camera_base"));
    panda.T_flange_holder = rigid_from_json(pose.at("T_flange_holder"));
    panda.joints = JointLog::read(scan.resolve(panda.joints_csv), scan.projections.count);
    if (const auto offsets = pose.find("joint_offsets_rad")) {
      const std::vector<double> q = offsets->numbers(panda::kJointCount);
      std::copy(q.begin(), q.end(), panda.joint_offsets_rad.begin());
    }
    scan.panda = std::move(panda);
  } else if (kind == "matrices") {
    pose.warn_unknown_keys({"kind", "file"});
    MatricesPoseSource matrices;
    matrices.file = pose.at("file").string();
    require_readable(scan, pose.at("file"), matrices.file);
    matrices.geometry = read_geometry(scan.resolve(matrices.file));
    const int n = static_cast<int>(matrices.geometry.views.size());
    if (n != scan.projections.count)
      pose.at("file").fail("holds " + std::to_string(n) + " views but projections.count is " +
                           std::to_string(scan.projections.count));
    scan.matrices = std::move(matrices);
  } else {
    pose.at("kind").fail("expected \"panda\" or \"matrices\", got \"" + kind + "\"");
  }

  if (auto holder = top.find("holder")) {
    // The holder spelt out, or a ctk-holder/1 file shared by the scans of one holder.
    if (holder->raw().is_string()) {
      const std::string name = holder->string();
      require_readable(scan, *holder, name);
      scan.holder = read_holder_file(scan.resolve(name));
      scan.holder_file = ScanDescription::HolderFileReference{name, *scan.holder};
    } else {
      scan.holder = holder_from_json(*holder);
    }
  }
  scan.stored_detector = scan.detector;
  if (auto binning = top.at("detector").find("binning")) {
    const int b = binning->integer();
    if (b < 1 || b > scan.detector.cols || b > scan.detector.rows)
      binning->fail("expected a whole number from 1 to the detector's smaller side (" +
                    std::to_string(std::min(scan.detector.cols, scan.detector.rows)) + "), got " + std::to_string(b));
    if (scan.matrices) {
      const Detector& g = scan.matrices->geometry.detector;
      const Detector binned = binned_detector(scan.detector, b);
      if (!(g.cols == scan.detector.cols && g.rows == scan.detector.rows) && !(g.cols == binned.cols && g.rows == binned.rows))
        top.at("pose_source")
            .at("file")
            .fail("its detector is " + std::to_string(g.cols) + " x " + std::to_string(g.rows) + ", neither the stored " +
                  std::to_string(scan.detector.cols) + " x " + std::to_string(scan.detector.rows) + " nor the binned " +
                  std::to_string(binned.cols) + " x " + std::to_string(binned.rows));
    }
    bin_scan(scan, b);
  }
  return scan;
}

nlohmann::json scan_to_json(const ScanDescription& scan) {
  using nlohmann::json;
  json j;
  j["format"] = kFormat;
  j["provenance"] = provenance();
  if (!scan.written_by_run.empty()) j["written_by"] = {{"run", scan.written_by_run}};
  // The file states the stored images; a binned scan's pixel positions go back to stored pixels.
  const int b = scan.binning;
  const Detector& stored = b > 1 ? scan.stored_detector : scan.detector;
  const Eigen::Vector2d principal_point = unbinned_pixel(scan.principal_point_px, b);
  j["detector"] = {{"cols", stored.cols},
                   {"rows", stored.rows},
                   {"pixel_pitch_mm", {stored.pitch_u_mm, stored.pitch_v_mm}},
                   {"principal_point_px", {principal_point.x(), principal_point.y()}}};
  if (b > 1) j["detector"]["binning"] = b;
  if (scan.distortion) {
    const RadialDistortion d = unbinned_distortion(*scan.distortion, b);
    j["detector"]["radial_distortion"] = {{"k1_per_px2", d.k1_per_px2}, {"center_px", {d.centre_px.x(), d.centre_px.y()}}};
  }
  j["source_to_detector_mm"] = scan.source_to_detector_mm;
  if (scan.source_drift_mm_per_100_views != Eigen::Vector2d::Zero())
    j["source_drift_mm_per_100_views"] = {scan.source_drift_mm_per_100_views.x(), scan.source_drift_mm_per_100_views.y()};
  const auto& p = scan.projections;
  json proj;
  if (p.file_names.empty())
    proj["files"] = p.files_pattern;
  else
    proj["files"] = p.file_names;
  proj["count"] = p.count;
  proj["kind"] = p.kind == ProjectionKind::counts ? "counts" : "line_integrals";
  if (p.kind == ProjectionKind::counts) {
    proj["flat"] = frame_names_to_json(p.flat);
    proj["dark"] = frame_names_to_json(p.dark);
  }
  j["projections"] = proj;
  if (scan.panda) {
    j["pose_source"] = {{"kind", "panda"},
                        {"joints_csv", scan.panda->joints_csv},
                        {"T_camera_base", rigid_to_json(scan.panda->T_camera_base)},
                        {"T_flange_holder", rigid_to_json(scan.panda->T_flange_holder)}};
    if (scan.panda->joint_offsets_rad != panda::Joints{}) j["pose_source"]["joint_offsets_rad"] = scan.panda->joint_offsets_rad;
  } else if (scan.matrices) {
    j["pose_source"] = {{"kind", "matrices"}, {"file", scan.matrices->file}};
  }
  if (scan.holder) {
    // A holder still as its file described it is declared by naming the file; one a workflow
    // changed (a diagnosis moving spheres or measuring the wall) is spelt out.
    const nlohmann::json spelt = holder_to_json(*scan.holder);
    const bool as_filed = scan.holder_file && holder_to_json(scan.holder_file->as_filed) == spelt;
    j["holder"] = as_filed ? nlohmann::json(scan.holder_file->name) : spelt;
  }
  return j;
}

void write_scan(const ScanDescription& scan, const fs::path& file) {
  write_text_atomically(file, scan_to_json(scan).dump(2) + "\n");
}

}  // namespace ctk

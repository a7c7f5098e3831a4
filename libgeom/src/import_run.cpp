#include "ctk/geom/import_run.hpp"

#include <cmath>
#include <sstream>
#include <stdexcept>

#include "ctk/core/error.hpp"
#include "ctk/core/file_names.hpp"
#include "ctk/core/image_io.hpp"
#include "ctk/core/nexus_tomo.hpp"
#include "ctk/core/output_set.hpp"
#include "ctk/geom/geometry_summary.hpp"
#include "ctk/geom/nikon_xtekct.hpp"
#include "ctk/geom/run_files.hpp"

namespace ctk {

namespace {

namespace fs = std::filesystem;

template <class... Parts>
std::string text(const Parts&... parts) {
  std::ostringstream s;
  (s << ... << parts);
  return s.str();
}

// The projections as the scan will name them: a quoted glob taken in natural order (a shell's own
// glob sorts 10 before 2), a printf pattern with its count, or the names.
ProjectionSet projection_set(const ProjectionImportRequest& r, const char* request) {
  ProjectionSet p;
  const std::string& first = r.files.front();
  if (r.files.size() == 1 && is_glob(first)) {
    const fs::path glob(first);
    for (const fs::path& f : matching_files(glob.parent_path(), glob.filename().string())) p.file_names.push_back(f.string());
    if (p.file_names.empty()) throw InputError(r.name(request, "files"), "", "no file matches '" + first + "'");
    p.count = static_cast<int>(p.file_names.size());
    if (r.count > 0 && r.count != p.count)
      throw InputError(r.name(request, "count"), "", text(r.count, " but '", first, "' matches ", p.count, " files"));
  } else if (r.files.size() == 1 && first.find('%') != std::string::npos) {
    if (r.count <= 0) throw InputError(r.name(request, "files"), "", "a printf pattern needs a count");
    p.files_pattern = first;
    p.count = r.count;
  } else {
    p.file_names = r.files;
    p.count = static_cast<int>(r.files.size());
    if (r.count > 0 && r.count != p.count)
      throw InputError(r.name(request, "count"), "", text(r.count, " but the files are ", p.count, " names"));
  }
  if (r.kind == ProjectionKind::counts) {
    if (r.flat.empty() || r.dark.empty()) throw InputError(r.name(request, "kind"), "", "raw counts need flat and dark frames");
    p.kind = ProjectionKind::counts;
    p.flat = r.flat;
    p.dark = r.dark;
  }
  return p;
}

// The detector given, or the size of the first projection file there is (columns and rows swapped
// where the described image is the stored one transposed).
Detector described_detector(const ProjectionImportRequest& r, const ProjectionSet& p, const char* request, double pitch_u,
                            double pitch_v, std::vector<std::string>& notes, bool transposed = false) {
  if (r.detector) return Detector{(*r.detector)[0], (*r.detector)[1], pitch_u, pitch_v};
  for (int v = 0; v < p.count; ++v) {
    std::error_code ec;
    const fs::path file = p.file_name(v);
    if (!fs::is_regular_file(file, ec)) continue;
    const Image first = read_image(file);
    notes.push_back(text("detector ", first.cols, " x ", first.rows, " px, from ", file.string()));
    return transposed ? Detector{first.rows, first.cols, pitch_u, pitch_v} : Detector{first.cols, first.rows, pitch_u, pitch_v};
  }
  throw InputError(r.name(request, "files"), "",
                   text("none of the ", p.count, " projection files exists (the first is ", p.file_name(0), "), so ",
                        r.name(request, "detector"), " must be given"));
}

// The images the scan names, checked before anything is written: a wrong pattern or a wrong
// detector would otherwise surface only at calibrate or reconstruct, view by view.
void check_images(const ScanDescription& scan, const std::string& files, std::vector<std::string>& warnings) {
  const ProjectionCensus census = require_projection_files(scan, files, "");
  if (census.missing > 0)
    warnings.push_back(text(census.missing, " of ", scan.projections.count, " projection files do not exist (the first is ",
                            census.first_missing.string(), "); calibrate and reconstruct will reject those views"));
  read_image(census.first_present, scan.detector.cols, scan.detector.rows);  // names the file and both sizes where they differ
}

// The binning recorded in the scan; the matrices file keeps addressing stored pixels.
void bin_imported(ImportedScan& imported, const ImportRequest& r, const char* request) {
  try {
    bin_scan(imported.scan, r.bin);
  } catch (const std::invalid_argument&) {
    throw InputError(
        r.name(request, "bin"), "",
        text(r.bin, " does not fit the ", imported.scan.detector.cols, " x ", imported.scan.detector.rows, " detector"));
  }
}

// The files written together (`write`: whatever the scan needs besides itself and its matrices,
// then the scan to write), then the scan read back as every command will read it.
ImportRun publish(const std::function<ImportedScan()>& write, const ImportRequest& r, const char* request,
                  std::vector<std::string> notes, std::vector<std::string> warnings) {
  {
    OutputSet outputs;
    ImportedScan imported = write();
    bin_imported(imported, r, request);
    write_imported_scan(imported, r.out);
    outputs.publish();
  }
  ImportRun run;
  run.scan_file = r.out;
  run.scan = read_scan(r.out);
  run.notes = std::move(notes);
  run.warnings = std::move(warnings);
  run.warnings.insert(run.warnings.end(), run.scan.warnings.begin(), run.scan.warnings.end());
  return run;
}

// The imports of projection files named by the caller (circular, cone-vec, RTK, matrices): images
// checked, no output over an input (`geometry_field`: the geometry file read, if any), written together.
ImportRun finish(ImportedScan imported, const ProjectionImportRequest& r, const char* request, std::vector<std::string> notes,
                 const std::string& geometry_field = {}, const fs::path& geometry_file = {}) {
  std::vector<std::string> warnings;
  check_images(imported.scan, r.name(request, "files"), warnings);
  const ScanDescription& scan = imported.scan;
  RunFiles files;
  for (int v = 0; v < scan.projections.count; ++v)
    files.input(r.name(request, "files") + ": projection " + std::to_string(v), scan.projection_path(v));
  for (const std::string& f : scan.projections.flat) files.input(r.name(request, "flat"), scan.resolve(f));
  for (const std::string& d : scan.projections.dark) files.input(r.name(request, "dark"), scan.resolve(d));
  files.input(geometry_field, geometry_file);
  files.output(r.name(request, "out"), r.out);
  files.output("the matrices beside " + r.name(request, "out"), scan.resolve(scan.matrices->file));
  files.check();
  return publish([&] { return std::move(imported); }, r, request, std::move(notes), std::move(warnings));
}

fs::path beside(const fs::path& out, const std::string& suffix) {
  return fs::absolute(out).parent_path() / (out.stem().string() + suffix);
}

// validate()'s checks, naming the field as the request names it.
void require(const ImportRequest& r, bool ok, const char* type, const char* field, const std::string& expected, double value) {
  require_option(ok, r.name(type, field).c_str(), expected.c_str(), value);
}

void require_given(const ImportRequest& r, bool given, const char* type, const char* field, const std::string& what) {
  if (!given) throw std::invalid_argument(r.name(type, field) + ": expected " + what + ", got nothing");
}

void require_pitch(const ProjectionImportRequest& r, const char* type) {
  require(r, r.pitch_mm.size() == 1 || r.pitch_mm.size() == 2, type, "pitch_mm", "one value or u v",
          static_cast<double>(r.pitch_mm.size()));
}

}  // namespace

std::string ImportRequest::name(const char* type, const char* field) const {
  return field_names ? field_names(field) : std::string(type) + "." + field;
}

void ImportRequest::validate() const {
  require_given(*this, !out.empty(), "ImportRequest", "out", "the scan file to write");
  require(*this, bin >= 1, "ImportRequest", "bin", "a binning factor of 1 or more", bin);
}

void ProjectionImportRequest::validate() const {
  const char* type = "ProjectionImportRequest";
  ImportRequest::validate();
  require_given(*this, !files.empty(), type, "files", "a printf pattern, a glob or the names");
  require(*this, count >= 0, type, "count", "0 or more", count);
  if (detector)
    for (int n : *detector) require(*this, n >= 1, type, "detector", "columns and rows of 1 or more", n);
  require(*this, pitch_mm.size() <= 2, type, "pitch_mm", "one value or u v", static_cast<double>(pitch_mm.size()));
  for (double p : pitch_mm) require(*this, p > 0 && std::isfinite(p), type, "pitch_mm", "finite lengths above 0", p);
}

void CircularImportRequest::validate() const {
  const char* type = "CircularImportRequest";
  ProjectionImportRequest::validate();
  require_pitch(*this, type);
  require(*this, sod_mm > 0 && std::isfinite(sod_mm), type, "sod_mm", "a finite distance above 0", sod_mm);
  require(*this, sdd_mm > sod_mm && std::isfinite(sdd_mm), type, "sdd_mm",
          "a finite distance beyond " + name(type, "sod_mm") + " (" + text(sod_mm) +
              " mm: the rotation axis lies between the source and the detector)",
          sdd_mm);
  require(*this, std::isfinite(first_angle_deg), type, "first_angle_deg", "a finite angle", first_angle_deg);
  require(*this, std::isfinite(step_deg), type, "step_deg", "a finite angle", step_deg);
  require(*this, sense == 1 || sense == -1, type, "sense", "+1 or -1", sense);
}

void ConeVecImportRequest::validate() const {
  ProjectionImportRequest::validate();
  require_given(*this, !vectors.empty(), "ConeVecImportRequest", "vectors", "the vectors file");
}

void RtkImportRequest::validate() const {
  ProjectionImportRequest::validate();
  require_pitch(*this, "RtkImportRequest");
  require_given(*this, !geometry.empty(), "RtkImportRequest", "geometry", "RTK's geometry XML");
}

void MatricesImportRequest::validate() const {
  ProjectionImportRequest::validate();
  require_pitch(*this, "MatricesImportRequest");
  require(*this, !matrices.empty(), "MatricesImportRequest", "matrices", "one matrix per projection", 0);
}

void NxTomoImportRequest::validate() const {
  const char* type = "NxTomoImportRequest";
  ImportRequest::validate();
  require_given(*this, !nexus.empty(), type, "nexus", "the NXtomo file");
  if (const auto& d = setup.source_to_axis_mm)
    require(*this, *d > 0 && std::isfinite(*d), type, "setup.source_to_axis_mm", "a finite distance above 0", *d);
  if (const auto& d = setup.source_to_detector_mm)
    require(*this, *d > 0 && std::isfinite(*d), type, "setup.source_to_detector_mm", "a finite distance above 0", *d);
  if (setup.pitch_mm)
    for (double p : *setup.pitch_mm)
      require(*this, p > 0 && std::isfinite(p), type, "setup.pitch_mm", "finite lengths above 0", p);
  require(*this, setup.sense == 1 || setup.sense == -1, type, "setup.sense", "+1 or -1", setup.sense);
}

void NikonImportRequest::validate() const {
  ImportRequest::validate();
  require_given(*this, !xtekct.empty(), "NikonImportRequest", "xtekct", "the .xtekct file");
  require(*this, sense == 1 || sense == -1, "NikonImportRequest", "sense", "+1 or -1", sense);
}

std::string ImportRun::brief() const {
  std::string s = text("wrote ", scan_file.string(), " (", scan.projections.count, " views, detector ", scan.detector.cols, " x ",
                       scan.detector.rows);
  if (scan.binning > 1)
    s += text(", binned ", scan.binning, " x ", scan.binning, " from ", scan.stored_detector.cols, " x ",
              scan.stored_detector.rows);
  return s + ") and " + scan.resolve(scan.matrices->file).string();
}

std::string ImportRun::report() const {
  std::string s;
  for (const std::string& n : notes) s += n + "\n";
  return s + to_text(summarize_geometry(scan.matrices->geometry));
}

ImportRun run_import(const CircularImportRequest& r) {
  r.validate();
  const char* request = "CircularImportRequest";
  std::vector<std::string> notes;
  const ProjectionSet projections = projection_set(r, request);
  CircularOrbit orbit;
  orbit.detector = described_detector(r, projections, request, r.pitch_mm.front(), r.pitch_mm.back(), notes);
  orbit.principal_point_px = r.principal_point_px.value_or(orbit.detector.centre_px());
  orbit.source_to_axis_mm = r.sod_mm;
  orbit.source_to_detector_mm = r.sdd_mm;
  orbit.sense = r.sense;
  for (int k = 0; k < projections.count; ++k) orbit.angles_rad.push_back((r.first_angle_deg + k * r.step_deg) * M_PI / 180.0);
  std::vector<ProjectionMatrix> matrices;
  try {
    matrices = circular_matrices(orbit);
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(text(r.name(request, "pitch_mm"), ", ", r.name(request, "sod_mm"), ", ",
                                     r.name(request, "sdd_mm"), ", ", r.name(request, "principal_point_px"), ", ",
                                     r.name(request, "step_deg"), ": ", e.what()));
  }
  return finish(import_matrices(orbit.detector, matrices, projections, r.out), r, request, std::move(notes));
}

ImportRun run_import(const ConeVecImportRequest& r) {
  r.validate();
  const char* request = "ConeVecImportRequest";
  std::vector<std::string> notes;
  const ProjectionSet projections = projection_set(r, request);
  const std::vector<ConeVec> all = read_cone_vecs(r.vectors);
  std::vector<int> rows = r.vector_rows;
  if (rows.empty())
    for (int i = 0; i < projections.count; ++i) rows.push_back(i);
  if (static_cast<int>(rows.size()) != projections.count)
    throw InputError(r.name(request, "vector_rows"), "", text(rows.size(), " rows for ", projections.count, " projections"));
  const Eigen::Vector3d u0(all.at(0)[6], all.at(0)[7], all.at(0)[8]), v0(all.at(0)[9], all.at(0)[10], all.at(0)[11]);
  const Detector described = described_detector(r, projections, request, r.pitch_mm.empty() ? u0.norm() : r.pitch_mm.front(),
                                                r.pitch_mm.empty() ? v0.norm() : r.pitch_mm.back(), notes,
                                                r.orientation == StoredOrientation::transposed_flipped);
  const Eigen::Matrix3d to_stored = described_to_stored(r.orientation, described);
  std::vector<ProjectionMatrix> matrices;
  for (int row : rows) {
    if (row < 0 || row >= static_cast<int>(all.size()))
      throw InputError(r.vectors.string(), "row " + std::to_string(row),
                       text("out of range: the file has ", all.size(), " rows"));
    try {
      const ProjectionMatrix described_P = from_cone_vec(all[static_cast<std::size_t>(row)], described);
      matrices.push_back(ProjectionMatrix(to_stored * described_P.matrix()));
    } catch (const std::invalid_argument&) {
      throw InputError(r.vectors.string(), "row " + std::to_string(row),
                       "describes no cone-beam projection (the source in the detector's plane, a zero or repeated detector step, "
                       "or numbers too large to multiply)");
    }
  }
  return finish(import_matrices(stored_detector(r.orientation, described), matrices, projections, r.out), r, request,
                std::move(notes), r.name(request, "vectors"), r.vectors);
}

ImportRun run_import(const RtkImportRequest& r) {
  r.validate();
  const char* request = "RtkImportRequest";
  std::vector<std::string> notes;
  const ProjectionSet projections = projection_set(r, request);
  const RtkGeometry g = read_rtk_geometry(r.geometry);
  if (static_cast<int>(g.views.size()) != projections.count)
    throw InputError(r.geometry.string(), "", text(g.views.size(), " projections for ", projections.count, " files"));
  const RtkRows rows = r.rows.value_or(g.pixel_map());
  const Detector detector = described_detector(r, projections, request, r.pitch_mm.front(), r.pitch_mm.back(), notes);
  // The reader refused what from_rtk cannot take, but not every pitch a caller may give.
  std::vector<ProjectionMatrix> matrices;
  try {
    matrices = holder_matrices(g, detector, rows);
  } catch (const std::invalid_argument&) {
    throw InputError(r.geometry.string(), "",
                     text("with ", r.name(request, "pitch_mm"), " ", detector.pitch_u_mm, " x ", detector.pitch_v_mm,
                          " mm its projections describe no cone-beam projection (a pitch in the wrong unit?)"));
  }
  notes.push_back(text("pixel map ", to_string(rows), !r.rows && g.rows ? " (named by the file)" : ""));
  if (g.holder_z_on_rtk_y) notes.push_back("volume frame: written by ctk with the holder's z on RTK's y, turned back");
  return finish(import_matrices(detector, matrices, projections, r.out), r, request, std::move(notes),
                r.name(request, "geometry"), r.geometry);
}

ImportRun run_import(const MatricesImportRequest& r) {
  r.validate();
  const char* request = "MatricesImportRequest";
  std::vector<std::string> notes;
  const ProjectionSet projections = projection_set(r, request);
  if (static_cast<int>(r.matrices.size()) != projections.count)
    throw InputError(r.name(request, "matrices"), "",
                     text(r.matrices.size(), " matrices for ", projections.count, " projections"));
  const Detector detector = described_detector(r, projections, request, r.pitch_mm.front(), r.pitch_mm.back(), notes);
  return finish(import_matrices(detector, r.matrices, projections, r.out), r, request, std::move(notes));
}

ImportRun run_import(const NxTomoImportRequest& r, const std::function<void(int written, int total)>& progress) {
  r.validate();
  const char* request = "NxTomoImportRequest";
  const NxTomo scan = read_nxtomo(r.nexus, r.entry);
  const NxTomoPlan plan = plan_nxtomo_import(scan, r.setup);
  if (!(plan.orbit.source_to_axis_mm < plan.orbit.source_to_detector_mm))
    throw InputError(r.name(request, "setup.source_to_axis_mm"), "",
                     text("the rotation axis must lie between the source and the detector (source to axis ",
                          plan.orbit.source_to_axis_mm, " mm, to the detector ", plan.orbit.source_to_detector_mm, " mm)"));
  std::vector<std::string> notes{text(r.nexus.string(), " ", scan.entry, ": ", scan.frames, " frames of ", scan.cols, " x ",
                                      scan.rows, " (", plan.projections.size(), " projections, ", plan.flats.size(), " flats, ",
                                      plan.darks.size(), " darks)")};
  for (const std::string& n : plan.notes) notes.push_back("  " + n);
  RunFiles files;
  files.input(r.name(request, "nexus"), r.nexus);
  files.output(r.name(request, "out"), r.out);
  files.output("the matrices beside " + r.name(request, "out"), beside(r.out, ".matrices.json"));
  const fs::path frames = beside(r.out, ".frames");
  files.output_folder("the frames beside " + r.name(request, "out"), frames);
  files.check();
  std::error_code ec;
  const bool had_frames = fs::exists(frames, ec);
  try {
    return publish([&] { return import_nxtomo(scan, plan, r.out, progress); }, r, request, std::move(notes), {});
  } catch (...) {
    if (!had_frames) fs::remove(frames, ec);  // the folder it made, if empty: the frames written went with the run
    throw;
  }
}

ImportRun run_import(const NikonImportRequest& r) {
  r.validate();
  const char* request = "NikonImportRequest";
  const NikonScan scan = read_xtekct(r.xtekct);
  const std::vector<fs::path> images = nikon_projection_files(scan);
  std::vector<std::string> warnings = scan.warnings;
  std::vector<std::string> notes{text(r.xtekct.string(), ": ", scan.projections, " projections in ", scan.input_folder.string(),
                                      ", white level ", scan.white_level)};
  ProjectionSet set;
  for (const fs::path& f : images) set.file_names.push_back(f.string());
  set.count = scan.projections;
  set.kind = ProjectionKind::counts;
  set.flat = {beside(r.out, ".white-level.tif").string()};
  set.dark = {beside(r.out, ".zero-dark.tif").string()};
  ImportedScan imported = import_matrices(scan.detector, nikon_matrices(scan, r.sense), set, r.out);
  check_images(imported.scan, r.name(request, "xtekct"), warnings);
  RunFiles files;
  files.input(r.name(request, "xtekct"), r.xtekct);
  for (int v = 0; v < set.count; ++v)
    files.input(r.name(request, "xtekct") + ": projection " + std::to_string(v), images[static_cast<std::size_t>(v)]);
  files.output(r.name(request, "out"), r.out);
  files.output("the matrices beside " + r.name(request, "out"), imported.scan.resolve(imported.scan.matrices->file));
  files.output("the white level beside " + r.name(request, "out"), set.flat.front());
  files.output("the zero dark beside " + r.name(request, "out"), set.dark.front());
  files.check();
  // Nikon normalises by one white level and no dark: both as images, so the scan stays ctk-scan/1.
  const auto write_levels = [&] {
    const std::size_t n = static_cast<std::size_t>(scan.detector.cols) * static_cast<std::size_t>(scan.detector.rows);
    write_image_float(Image{scan.detector.cols, scan.detector.rows, std::vector<float>(n, static_cast<float>(scan.white_level))},
                      set.flat.front());
    write_image_uint16(Image{scan.detector.cols, scan.detector.rows, std::vector<float>(n, 0.0f)}, set.dark.front());
    return std::move(imported);
  };
  return publish(write_levels, r, request, std::move(notes), std::move(warnings));
}

}  // namespace ctk

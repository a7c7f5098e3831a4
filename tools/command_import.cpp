// ctk import: a scan described elsewhere becomes a ctk-scan/1 file with a "matrices" pose source
// (and its ctk-geometry/1 file beside it), so no one writes JSON by hand.
//   ctk import circular  — a circular orbit by its numbers (SOD, SDD, pitch, angles, principal point, sense)
//   ctk import cone-vec  — per-view ASTRA cone_vec rows (e.g. a CWI ".geom" file)
#include <cmath>
#include <filesystem>
#include <iostream>
#include <sstream>
#include <stdexcept>

#include "commands.hpp"
#include "ctk/core/output_set.hpp"
#include "ctk/geom/run_files.hpp"
#include "option_checks.hpp"
#include "ctk/core/error.hpp"
#include "ctk/geom/scan_import.hpp"
#include "ctk/core/image_io.hpp"

namespace ctk::tools {

namespace {

namespace fs = std::filesystem;

// What both forms share: the projection files and how to turn them into line integrals.
struct ProjectionOptions {
  std::vector<std::string> files;  // one printf pattern (with --count) or a list of names
  int count = 0;
  std::string kind = "counts";
  std::vector<std::string> flat, dark;
  std::vector<int> detector;  // cols rows (of the image the geometry describes)
  std::vector<double> pitch;  // mm: one value or u v
  fs::path out;
};

struct CircularOptions : ProjectionOptions {
  double sod = 0, sdd = 0, first_angle_deg = 0, step_deg = 0;
  std::vector<double> principal_point;
  int sense = 1;
};

struct ConeVecOptions : ProjectionOptions {
  fs::path vectors;
  std::vector<int> vector_rows;
  std::string orientation = "as-described";
};

void add_projection_options(CLI::App* cmd, ProjectionOptions& o, bool pitch_required) {
  cmd->add_option("--out", o.out, "scan.json to write (the matrices go beside it as <stem>.matrices.json)")->required();
  cmd->add_option("--files", o.files, "Projection files: a printf pattern (with --count) or the names in view order")->required();
  cmd->add_option("--count", o.count, "Number of projections when --files is a pattern")->check(positive_number);
  cmd->add_option("--kind", o.kind, "counts (raw, needs --flat and --dark) or line_integrals")
      ->check(CLI::IsMember({"counts", "line_integrals"}))
      ->capture_default_str();
  cmd->add_option("--flat", o.flat, "Flat (open-beam) frame(s); several are averaged");
  cmd->add_option("--dark", o.dark, "Dark (offset) frame(s); several are averaged");
  cmd->add_option("--detector", o.detector, "Columns and rows of the image the geometry describes")
      ->expected(2)
      ->required()
      ->check(positive_number);
  auto* pitch =
      cmd->add_option("--pitch", o.pitch, "Pixel pitch in mm: one value or u v")->expected(1, 2)->check(positive_number);
  if (pitch_required) pitch->required();
}

ProjectionSet projection_set(const ProjectionOptions& o) {
  ProjectionSet p;
  const bool pattern = o.files.size() == 1 && o.files.front().find('%') != std::string::npos;
  if (pattern) {
    if (o.count <= 0) throw InputError("--files", "", "a printf pattern needs --count");
    p.files_pattern = o.files.front();
    p.count = o.count;
  } else {
    p.file_names = o.files;
    p.count = static_cast<int>(o.files.size());
    if (o.count > 0 && o.count != p.count)
      throw InputError("--count", "", std::to_string(o.count) + " but --files lists " + std::to_string(p.count) + " names");
  }
  if (o.kind == "counts") {
    if (o.flat.empty() || o.dark.empty()) throw InputError("--kind counts", "", "raw counts need --flat and --dark");
    p.kind = ProjectionKind::counts;
    p.flat = o.flat;
    p.dark = o.dark;
  }
  return p;
}

Detector described_detector(const ProjectionOptions& o, double pitch_u, double pitch_v) {
  return Detector{o.detector[0], o.detector[1], pitch_u, pitch_v};
}

// The images the scan names, checked before anything is written: a wrong pattern or a wrong
// --detector would otherwise surface only at calibrate or reconstruct, view by view. Some missing
// files are allowed (those views are rejected there, with the reason); none, or most, are not.
void check_images(const ScanDescription& scan) {
  const ProjectionCensus census = require_projection_files(scan, "--files", "");
  if (census.missing > 0)
    std::cerr << "warning: " << census.missing << " of " << scan.projections.count
              << " projection files do not exist (the first is " << census.first_missing.string()
              << "); calibrate and reconstruct will reject those views\n";
  read_image(census.first_present, scan.detector.cols, scan.detector.rows);  // names the file and both sizes where they differ
}

// `vectors`: the geometry file read, if any.
void finish(const ImportedScan& imported, const fs::path& out, const fs::path& vectors = {}) {
  const ScanDescription& scan = imported.scan;
  check_images(scan);
  RunFiles files;
  for (int v = 0; v < scan.projections.count; ++v)
    files.input("--files: projection " + std::to_string(v), scan.projection_path(v));
  for (const std::string& f : scan.projections.flat) files.input("--flat", scan.resolve(f));
  for (const std::string& d : scan.projections.dark) files.input("--dark", scan.resolve(d));
  files.input("--vectors", vectors);
  files.output("--out", out);
  files.output("the matrices beside --out", scan.resolve(scan.matrices->file));
  files.check();
  {
    OutputSet outputs;  // the matrices and the scan that names them, together
    write_imported_scan(imported, out);
    outputs.publish();
  }
  const ScanDescription check = read_scan(out);  // what every other command will read
  for (const auto& w : check.warnings) std::cerr << "warning: " << w << "\n";
  std::cout << "wrote " << out.string() << " (" << check.projections.count << " views, detector " << check.detector.cols << " x "
            << check.detector.rows << ") and " << check.resolve(check.matrices->file).string() << "\n";
}

void run_circular(const CircularOptions& o) {
  const ProjectionSet projections = projection_set(o);
  if (!(o.sod < o.sdd))
    throw InputError("--sod", "",
                     (std::ostringstream() << o.sod << " mm is not less than --sdd " << o.sdd
                                           << " mm: the rotation axis lies between the source and the detector")
                         .str());
  const double pu = o.pitch.front(), pv = o.pitch.back();
  CircularOrbit orbit;
  orbit.detector = described_detector(o, pu, pv);
  orbit.principal_point_px =
      o.principal_point.empty() ? orbit.detector.centre_px() : Eigen::Vector2d(o.principal_point[0], o.principal_point[1]);
  orbit.source_to_axis_mm = o.sod;
  orbit.source_to_detector_mm = o.sdd;
  orbit.sense = o.sense;
  for (int k = 0; k < projections.count; ++k) orbit.angles_rad.push_back((o.first_angle_deg + k * o.step_deg) * M_PI / 180.0);
  const std::vector<ProjectionMatrix> matrices = circular_matrices(orbit);
  finish(import_matrices(orbit.detector, matrices, projections, o.out), o.out);
}

void run_cone_vec(const ConeVecOptions& o) {
  const ProjectionSet projections = projection_set(o);
  const std::vector<ConeVec> all = read_cone_vecs(o.vectors);
  std::vector<int> rows = o.vector_rows;
  if (rows.empty())
    for (int i = 0; i < projections.count; ++i) rows.push_back(i);
  if (static_cast<int>(rows.size()) != projections.count)
    throw InputError("--vector-rows", "",
                     std::to_string(rows.size()) + " rows for " + std::to_string(projections.count) + " projections");
  const Eigen::Vector3d u0(all.at(0)[6], all.at(0)[7], all.at(0)[8]), v0(all.at(0)[9], all.at(0)[10], all.at(0)[11]);
  const Detector described =
      described_detector(o, o.pitch.empty() ? u0.norm() : o.pitch.front(), o.pitch.empty() ? v0.norm() : o.pitch.back());
  const StoredOrientation orientation = stored_orientation_from_string(o.orientation);
  const Eigen::Matrix3d to_stored = described_to_stored(orientation, described);
  std::vector<ProjectionMatrix> matrices;
  for (int r : rows) {
    if (r < 0 || r >= static_cast<int>(all.size()))
      throw InputError(o.vectors.string(), "row " + std::to_string(r),
                       "out of range: the file has " + std::to_string(all.size()) + " rows");
    try {
      const ProjectionMatrix described_P = from_cone_vec(all[static_cast<std::size_t>(r)], described);
      matrices.push_back(ProjectionMatrix(to_stored * described_P.matrix()));
    } catch (const std::invalid_argument&) {
      throw InputError(o.vectors.string(), "row " + std::to_string(r),
                       "describes no cone-beam projection (the source in the detector's plane, a zero or repeated detector step, "
                       "or numbers too large to multiply)");
    }
  }
  finish(import_matrices(stored_detector(orientation, described), matrices, projections, o.out), o.out, o.vectors);
}

}  // namespace

void register_import(CLI::App& app) {
  CLI::App* cmd = app.add_subcommand("import", "Turn a scan described elsewhere into ctk-scan/1 with per-view matrices");
  cmd->require_subcommand(1);

  auto c = std::make_shared<CircularOptions>();
  CLI::App* circular = cmd->add_subcommand(
      "circular",
      "A circular orbit: view k at angle first + k step; volume frame with the rotation axis on +z; at t = sense * angle the "
      "source is at SOD (sin t, cos t, 0), columns run along (cos t, -sin t, 0), rows along -z");
  add_projection_options(circular, *c, true);
  circular->add_option("--sod", c->sod, "Source to rotation axis, mm")->required()->check(positive_number);
  circular->add_option("--sdd", c->sdd, "Source to detector, mm")->required()->check(positive_number);
  circular->add_option("--first-angle", c->first_angle_deg, "Angle of view 0, degrees")->capture_default_str();
  circular->add_option("--step", c->step_deg, "Angle between views, degrees")->required();
  circular
      ->add_option("--principal-point", c->principal_point,
                   "u0 v0 in pixels: where the central ray meets the detector (u0 is also the rotation axis' column); default: "
                   "the detector centre")
      ->expected(2);
  circular->add_option("--sense", c->sense, "Rotation sense, +1 or -1")->check(CLI::IsMember({1, -1}))->capture_default_str();
  circular->callback([c] { run_circular(*c); });

  auto v = std::make_shared<ConeVecOptions>();
  CLI::App* cone_vec =
      cmd->add_subcommand("cone-vec", "ASTRA cone_vec rows (source, detector centre, column step, row step), mm");
  add_projection_options(cone_vec, *v, false);
  cone_vec->add_option("--vectors", v->vectors, "Text file, 12 numbers per line")->required()->check(CLI::ExistingFile);
  cone_vec->add_option("--vector-rows", v->vector_rows,
                       "Row of the vectors file for each projection, in view order (default: 0, 1, ...)");
  cone_vec
      ->add_option("--orientation", v->orientation,
                   "How the stored files relate to the image the vectors describe: as-described, or transpose-flipud "
                   "(described = transpose(flipud(stored)), as the CWI walnut loader does)")
      ->check(CLI::IsMember({"as-described", "transpose-flipud"}))
      ->capture_default_str();
  cone_vec->callback([v] { run_cone_vec(*v); });
}

}  // namespace ctk::tools

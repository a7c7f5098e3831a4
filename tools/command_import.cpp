// ctk import: a scan described elsewhere becomes a ctk-scan/1 file with a "matrices" pose source
// (and its ctk-geometry/1 file beside it), so no one writes JSON by hand.
//   ctk import circular  — a circular orbit by its numbers (SOD, SDD, pitch, angles, principal point, sense)
//   ctk import cone-vec  — per-view ASTRA cone_vec rows (e.g. a CWI ".geom" file)
//   ctk import rtk       — RTK's geometry XML (RTKThreeDCircularGeometry)
//   ctk import nxtomo    — an HDF5/NeXus NXtomo file (frames copied out as TIFF)
//   ctk import nikon     — a Nikon .xtekct file beside its TIFF projections
#include <cmath>
#include <filesystem>
#include <functional>
#include <iostream>
#include <optional>
#include <sstream>
#include <stdexcept>

#include "commands.hpp"
#include "ctk/core/output_set.hpp"
#include "ctk/geom/run_files.hpp"
#include "option_checks.hpp"
#include "ctk/core/error.hpp"
#include "ctk/geom/geometry_summary.hpp"
#include "ctk/geom/rtk_geometry.hpp"
#include "ctk/geom/scan_import.hpp"
#include "ctk/core/file_names.hpp"
#include "ctk/core/image_io.hpp"
#include "ctk/core/nexus_tomo.hpp"
#include "ctk/geom/nikon_xtekct.hpp"
#include "ctk/geom/nxtomo_import.hpp"

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
  int bin = 1;
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

struct NxTomoOptions {
  fs::path nexus, out;
  std::string entry, kind = "counts";
  std::optional<double> sod, sdd;
  std::vector<double> pitch, principal_point;
  int sense = 1, bin = 1;
};

struct NikonOptions {
  fs::path xtekct, out;
  int sense = 1, bin = 1;
};

struct RtkOptions : ProjectionOptions {
  fs::path geometry;
  std::string rows;  // empty: what the file's ctk comment names, else as-stored
};

// Recorded in the scan (detector.binning): every command then bins the images as it reads them.
void add_bin_option(CLI::App* cmd, int& bin) {
  cmd->add_option("--bin", bin, "Bin the detector n x n in every command that reads the scan (counts summed, pitch scaled)")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
}

void add_projection_options(CLI::App* cmd, ProjectionOptions& o, bool pitch_required) {
  cmd->add_option("--out", o.out, "scan.json to write (the matrices go beside it as <stem>.matrices.json)")->required();
  cmd->add_option("--files", o.files, "Projection files: a printf pattern (with --count) or the names in view order")->required();
  cmd->add_option("--count", o.count, "Number of projections when --files is a pattern")->check(positive_number);
  cmd->add_option("--kind", o.kind, "counts (raw, needs --flat and --dark) or line_integrals")
      ->check(CLI::IsMember({"counts", "line_integrals"}))
      ->capture_default_str();
  cmd->add_option("--flat", o.flat, "Flat (open-beam) frame(s); several are averaged");
  cmd->add_option("--dark", o.dark, "Dark (offset) frame(s); several are averaged");
  cmd->add_option("--detector", o.detector,
                  "Columns and rows of the image the geometry describes (default: the first projection file's size)")
      ->expected(2)
      ->check(positive_number);
  auto* pitch =
      cmd->add_option("--pitch", o.pitch, "Pixel pitch in mm: one value or u v")->expected(1, 2)->check(positive_number);
  if (pitch_required) pitch->required();
  add_bin_option(cmd, o.bin);
}

ProjectionSet projection_set(const ProjectionOptions& o) {
  ProjectionSet p;
  const bool pattern = o.files.size() == 1 && o.files.front().find('%') != std::string::npos;
  if (o.files.size() == 1 && is_glob(o.files.front())) {
    // A quoted glob: the files it matches in natural order (a shell's own glob sorts 10 before 2).
    const fs::path glob(o.files.front());
    for (const fs::path& f : matching_files(glob.parent_path(), glob.filename().string())) p.file_names.push_back(f.string());
    if (p.file_names.empty()) throw InputError("--files", "", "no file matches '" + o.files.front() + "'");
    p.count = static_cast<int>(p.file_names.size());
    if (o.count > 0 && o.count != p.count)
      throw InputError("--count", "",
                       std::to_string(o.count) + " but '" + o.files.front() + "' matches " + std::to_string(p.count) + " files");
  } else if (pattern) {
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

// --detector, or the size of the first projection file there is (columns and rows swapped where
// the described image is the stored one transposed).
Detector described_detector(const ProjectionOptions& o, const ProjectionSet& p, double pitch_u, double pitch_v,
                            bool transposed = false) {
  if (!o.detector.empty()) return Detector{o.detector[0], o.detector[1], pitch_u, pitch_v};
  for (int v = 0; v < p.count; ++v) {
    std::error_code ec;
    const fs::path file = p.file_name(v);
    if (!fs::is_regular_file(file, ec)) continue;
    const Image first = read_image(file);
    std::cout << "detector " << first.cols << " x " << first.rows << " px, from " << file.string() << "\n";
    return transposed ? Detector{first.rows, first.cols, pitch_u, pitch_v} : Detector{first.cols, first.rows, pitch_u, pitch_v};
  }
  throw InputError("--files", "",
                   "none of the " + std::to_string(p.count) + " projection files exists (the first is " + p.file_name(0) +
                       "), so --detector must be given");
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

// --bin, recorded in the scan (detector.binning); the matrices file keeps addressing stored pixels.
void bin_imported(ImportedScan& imported, int bin) {
  try {
    bin_scan(imported.scan, bin);
  } catch (const std::invalid_argument&) {
    throw InputError("--bin", "",
                     std::to_string(bin) + " does not fit the " + std::to_string(imported.scan.detector.cols) + " x " +
                         std::to_string(imported.scan.detector.rows) + " detector");
  }
}

// The scan read back as every other command will read it, and the geometry it describes.
void report_written(const fs::path& out) {
  const ScanDescription check = read_scan(out);
  for (const auto& w : check.warnings) std::cerr << "warning: " << w << "\n";
  std::cout << "wrote " << out.string() << " (" << check.projections.count << " views, detector " << check.detector.cols << " x "
            << check.detector.rows;
  if (check.binning > 1)
    std::cout << ", binned " << check.binning << " x " << check.binning << " from " << check.stored_detector.cols << " x "
              << check.stored_detector.rows;
  std::cout << ") and " << check.resolve(check.matrices->file).string() << "\n"
            << to_text(summarize_geometry(check.matrices->geometry));
}

// `geometry_file`: the geometry file read, if any, and the option that named it.
void finish(ImportedScan imported, const fs::path& out, int bin, const std::string& geometry_option = {},
            const fs::path& geometry_file = {}) {
  check_images(imported.scan);
  bin_imported(imported, bin);
  const ScanDescription& scan = imported.scan;
  RunFiles files;
  for (int v = 0; v < scan.projections.count; ++v)
    files.input("--files: projection " + std::to_string(v), scan.projection_path(v));
  for (const std::string& f : scan.projections.flat) files.input("--flat", scan.resolve(f));
  for (const std::string& d : scan.projections.dark) files.input("--dark", scan.resolve(d));
  files.input(geometry_option, geometry_file);
  files.output("--out", out);
  files.output("the matrices beside --out", scan.resolve(scan.matrices->file));
  files.check();
  {
    OutputSet outputs;  // the matrices and the scan that names them, together
    write_imported_scan(imported, out);
    outputs.publish();
  }
  report_written(out);
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
  orbit.detector = described_detector(o, projections, pu, pv);
  orbit.principal_point_px =
      o.principal_point.empty() ? orbit.detector.centre_px() : Eigen::Vector2d(o.principal_point[0], o.principal_point[1]);
  orbit.source_to_axis_mm = o.sod;
  orbit.source_to_detector_mm = o.sdd;
  orbit.sense = o.sense;
  for (int k = 0; k < projections.count; ++k) orbit.angles_rad.push_back((o.first_angle_deg + k * o.step_deg) * M_PI / 180.0);
  const std::vector<ProjectionMatrix> matrices = circular_matrices(orbit);
  finish(import_matrices(orbit.detector, matrices, projections, o.out), o.out, o.bin);
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
  const StoredOrientation orientation = stored_orientation_from_string(o.orientation);
  const Detector described =
      described_detector(o, projections, o.pitch.empty() ? u0.norm() : o.pitch.front(),
                         o.pitch.empty() ? v0.norm() : o.pitch.back(), orientation == StoredOrientation::transposed_flipped);
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
  finish(import_matrices(stored_detector(orientation, described), matrices, projections, o.out), o.out, o.bin, "--vectors",
         o.vectors);
}

void run_rtk(const RtkOptions& o) {
  const ProjectionSet projections = projection_set(o);
  const RtkGeometry g = read_rtk_geometry(o.geometry);
  if (static_cast<int>(g.views.size()) != projections.count)
    throw InputError(o.geometry.string(), "",
                     std::to_string(g.views.size()) + " projections for " + std::to_string(projections.count) + " files");
  const RtkRows rows = !o.rows.empty() ? rtk_rows_from_string(o.rows) : g.pixel_map();
  const Detector detector = described_detector(o, projections, o.pitch.front(), o.pitch.back());
  std::vector<ProjectionMatrix> matrices;
  for (const RtkProjection& v : g.views)
    matrices.push_back(from_rtk(v, detector, rows));  // the reader refused what this cannot take
  std::cout << "pixel map " << to_string(rows) << (o.rows.empty() && g.rows ? " (named by the file)" : "") << "\n";
  finish(import_matrices(detector, matrices, projections, o.out), o.out, o.bin, "--geometry", o.geometry);
}

// The scan's files written together (frames, matrices, scan), then read back as every command will.
void publish_scan(const std::function<ImportedScan()>& write_frames, const fs::path& out, int bin) {
  {
    OutputSet outputs;
    ImportedScan imported = write_frames();
    bin_imported(imported, bin);
    write_imported_scan(imported, out);
    outputs.publish();
  }
  report_written(out);
}

void run_nxtomo(const NxTomoOptions& o) {
  const NxTomo scan = read_nxtomo(o.nexus, o.entry);
  NxTomoSetup setup;
  setup.source_to_axis_mm = o.sod;
  setup.source_to_detector_mm = o.sdd;
  if (!o.pitch.empty()) setup.pitch_mm = Eigen::Vector2d(o.pitch.front(), o.pitch.back());
  if (!o.principal_point.empty()) setup.principal_point_px = Eigen::Vector2d(o.principal_point[0], o.principal_point[1]);
  setup.sense = o.sense;
  setup.line_integrals = o.kind == "line_integrals";
  const NxTomoPlan plan = plan_nxtomo_import(scan, setup);
  if (!(plan.orbit.source_to_axis_mm < plan.orbit.source_to_detector_mm))
    throw InputError("--sod", "",
                     "the rotation axis must lie between the source and the detector (source to axis " +
                         std::to_string(plan.orbit.source_to_axis_mm) + " mm, to the detector " +
                         std::to_string(plan.orbit.source_to_detector_mm) + " mm)");
  std::cout << o.nexus.string() << " " << scan.entry << ": " << scan.frames << " frames of " << scan.cols << " x " << scan.rows
            << " (" << plan.projections.size() << " projections, " << plan.flats.size() << " flats, " << plan.darks.size()
            << " darks)\n";
  for (const std::string& n : plan.notes) std::cout << "  " << n << "\n";
  const fs::path frames = fs::absolute(o.out).parent_path() / (o.out.stem().string() + ".frames");
  RunFiles files;
  files.input("--nexus", o.nexus);
  files.output("--out", o.out);
  files.output("the matrices beside --out", fs::absolute(o.out).parent_path() / (o.out.stem().string() + ".matrices.json"));
  files.output_folder("the frames beside --out", frames);
  files.check();
  publish_scan(
      [&] {
        return import_nxtomo(scan, plan, o.out, [](int written, int total) {
          if (written == total || written % 50 == 0)
            std::cout << "\r  frames " << written << " of " << total << (written == total ? "\n" : "") << std::flush;
        });
      },
      o.out, o.bin);
}

void run_nikon(const NikonOptions& o) {
  const NikonScan scan = read_xtekct(o.xtekct);
  const std::vector<fs::path> images = nikon_projection_files(scan);
  for (const std::string& w : scan.warnings) std::cerr << "warning: " << w << "\n";
  std::cout << o.xtekct.string() << ": " << scan.projections << " projections in " << scan.input_folder.string()
            << ", white level " << scan.white_level << "\n";
  ProjectionSet set;
  for (const fs::path& f : images) set.file_names.push_back(f.string());
  set.count = scan.projections;
  set.kind = ProjectionKind::counts;
  const std::string stem = o.out.stem().string();
  const fs::path folder = fs::absolute(o.out).parent_path();
  set.flat = {(folder / (stem + ".white-level.tif")).string()};
  set.dark = {(folder / (stem + ".zero-dark.tif")).string()};
  ImportedScan imported = import_matrices(scan.detector, nikon_matrices(scan, o.sense), set, o.out);
  check_images(imported.scan);
  RunFiles files;
  files.input("--xtekct", o.xtekct);
  for (int v = 0; v < set.count; ++v)
    files.input("--xtekct: projection " + std::to_string(v), images[static_cast<std::size_t>(v)]);
  files.output("--out", o.out);
  files.output("the matrices beside --out", imported.scan.resolve(imported.scan.matrices->file));
  files.output("the white level beside --out", set.flat.front());
  files.output("the zero dark beside --out", set.dark.front());
  files.check();
  publish_scan(
      [&] {
        // Nikon normalises by one white level and no dark: both as images, so the scan stays ctk-scan/1.
        const std::size_t n = static_cast<std::size_t>(scan.detector.cols) * static_cast<std::size_t>(scan.detector.rows);
        write_image_float(
            Image{scan.detector.cols, scan.detector.rows, std::vector<float>(n, static_cast<float>(scan.white_level))},
            set.flat.front());
        write_image_uint16(Image{scan.detector.cols, scan.detector.rows, std::vector<float>(n, 0.0f)}, set.dark.front());
        return imported;
      },
      o.out, o.bin);
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

  auto r = std::make_shared<RtkOptions>();
  CLI::App* rtk =
      cmd->add_subcommand("rtk",
                          "RTK's geometry XML, one <Projection> per file; RTK's detector coordinates (mm) become pixels by "
                          "u = (cols - 1) / 2 + x / pitch_u, v = (rows - 1) / 2 - y / pitch_v (RTK's y runs up the stored rows)");
  add_projection_options(rtk, *r, true);
  rtk->add_option("--geometry", r->geometry, "RTK geometry XML (RTKThreeDCircularGeometry, version 2 or 3)")
      ->required()
      ->check(CLI::ExistingFile);
  rtk->add_option("--rows", r->rows,
                  "as-stored: RTK indexed the images as stored (y = (v - (rows - 1) / 2) pitch); flipped: flipped vertically "
                  "(y = ((rows - 1) / 2 - v) pitch); default: what a file written by ctk names, else as-stored")
      ->check(CLI::IsMember({"as-stored", "flipped"}));
  rtk->callback([r] { run_rtk(*r); });

  auto n = std::make_shared<NxTomoOptions>();
  CLI::App* nxtomo = cmd->add_subcommand(
      "nxtomo",
      "An HDF5/NeXus NXtomo file: projections, flats and darks by image key, a circular orbit from the rotation angles; "
      "the frames are copied out as TIFF into <out stem>.frames/. NeXus' frame: the sample turns right-handed about the "
      "vertical by the angle, columns run along +x (to the left looking downstream), row 0 at the top");
  nxtomo->add_option("--nexus", n->nexus, "The NXtomo file (.nx, .nxs, .h5)")->required()->check(CLI::ExistingFile);
  nxtomo->add_option("--out", n->out, "scan.json to write (the matrices go beside it as <stem>.matrices.json)")->required();
  nxtomo->add_option("--entry", n->entry, "The NXentry to read (default: the first whose definition is NXtomo)");
  nxtomo->add_option("--sod", n->sod, "Source to rotation axis, mm (default: |instrument/source/distance|)")
      ->check(positive_number);
  nxtomo->add_option("--sdd", n->sdd, "Source to detector, mm (default: SOD + instrument/detector/distance)")
      ->check(positive_number);
  nxtomo->add_option("--pitch", n->pitch, "Pixel pitch in mm: one value or u v (default: the detector's x/y_pixel_size)")
      ->expected(1, 2)
      ->check(positive_number);
  nxtomo->add_option("--principal-point", n->principal_point, "u0 v0 in pixels (default: the detector centre)")->expected(2);
  nxtomo->add_option("--sense", n->sense, "Rotation sense, +1 or -1")->check(CLI::IsMember({1, -1}))->capture_default_str();
  nxtomo->add_option("--kind", n->kind, "counts (normalised by the flat and dark frames) or line_integrals")
      ->check(CLI::IsMember({"counts", "line_integrals"}))
      ->capture_default_str();
  add_bin_option(nxtomo, n->bin);
  nxtomo->callback([n] { run_nxtomo(*n); });

  auto k = std::make_shared<NikonOptions>();
  CLI::App* nikon = cmd->add_subcommand(
      "nikon",
      "A Nikon (X-Tek) scan: its .xtekct file and the <Name>_NNNN.tif projections beside it, placed as CIL's reader "
      "documents (axis offset, tilt and roll included), counts normalised by the white level");
  nikon->add_option("--xtekct", k->xtekct, "The .xtekct file")->required()->check(CLI::ExistingFile);
  nikon->add_option("--out", k->out, "scan.json to write (the matrices go beside it as <stem>.matrices.json)")->required();
  nikon->add_option("--sense", k->sense, "+1 as the file states, -1 the sample turning the other way")
      ->check(CLI::IsMember({1, -1}))
      ->capture_default_str();
  add_bin_option(nikon, k->bin);
  nikon->callback([k] { run_nikon(*k); });
}

}  // namespace ctk::tools

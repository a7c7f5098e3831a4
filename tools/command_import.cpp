// ctk import: a scan described elsewhere becomes a ctk-scan/1 file with a "matrices" pose source
// (and its ctk-geometry/1 file beside it), so no one writes JSON by hand: the options become an
// import request (libgeom/include/ctk/geom/import_run.hpp), and its run is printed.
//   ctk import circular  — a circular orbit by its numbers (SOD, SDD, pitch, angles, principal point, sense)
//   ctk import cone-vec  — per-view ASTRA cone_vec rows (e.g. a CWI ".geom" file)
//   ctk import rtk       — RTK's geometry XML (RTKThreeDCircularGeometry)
//   ctk import nxtomo    — an HDF5/NeXus NXtomo file (frames copied out as TIFF)
//   ctk import nikon     — a Nikon .xtekct file beside its TIFF projections
#include <iostream>
#include <map>
#include <memory>
#include <optional>

#include "commands.hpp"
#include "ctk/geom/import_run.hpp"
#include "interruption.hpp"
#include "option_checks.hpp"

namespace ctk::tools {

namespace {

namespace fs = std::filesystem;

// What CLI11 fills in a plain form and the request holds in its own (a kind, a detector, a point).
struct PlainArguments {
  std::string kind = "counts";
  std::vector<int> detector;
  std::vector<double> principal_point;
};

// The request's fields as this command's options, for its messages.
std::string option_named(const std::string& field) {
  static const std::map<std::string, std::string> options{
      {"pitch_mm", "--pitch"},
      {"sod_mm", "--sod"},
      {"sdd_mm", "--sdd"},
      {"first_angle_deg", "--first-angle"},
      {"step_deg", "--step"},
      {"principal_point_px", "--principal-point"},
      {"vector_rows", "--vector-rows"},
      {"setup.source_to_axis_mm", "--sod"},
      {"setup.source_to_detector_mm", "--sdd"},
      {"setup.pitch_mm", "--pitch"},
      {"setup.principal_point_px", "--principal-point"},
      {"setup.sense", "--sense"},
  };
  const auto named = options.find(field);
  return named != options.end() ? named->second : "--" + field;
}

template <class Request>
Request& with_arguments(Request& r, const PlainArguments& a) {
  r.kind = a.kind == "counts" ? ProjectionKind::counts : ProjectionKind::line_integrals;
  if (!a.detector.empty()) r.detector = std::array<int, 2>{a.detector[0], a.detector[1]};
  return r;
}

std::optional<Eigen::Vector2d> principal_point(const std::vector<double>& p) {
  if (p.empty()) return std::nullopt;
  return Eigen::Vector2d(p[0], p[1]);
}

void print(const ImportRun& run) {
  for (const std::string& w : run.warnings) std::cerr << "warning: " << w << "\n";
  std::cout << run.brief() << "\n" << run.report();
}

// Recorded in the scan (detector.binning): every command then bins the images as it reads them.
void add_bin_option(CLI::App* cmd, int& bin) {
  cmd->add_option("--bin", bin, "Bin the detector n x n in every command that reads the scan (counts summed, pitch scaled)")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
}

// Every import names --out; its messages name the options.
void add_out_option(CLI::App* cmd, ImportRequest& r) {
  r.field_names = option_named;
  cmd->add_option("--out", r.out, "scan.json to write (the matrices go beside it as <stem>.matrices.json)")->required();
}

void add_projection_options(CLI::App* cmd, ProjectionImportRequest& r, PlainArguments& a, bool pitch_required) {
  add_out_option(cmd, r);
  cmd->add_option("--files", r.files,
                  "Projection files: a printf pattern (with --count), a quoted glob or the names in view order")
      ->required();
  cmd->add_option("--count", r.count, "Number of projections when --files is a pattern")->check(positive_number);
  cmd->add_option("--kind", a.kind, "counts (raw, needs --flat and --dark) or line_integrals")
      ->check(CLI::IsMember({"counts", "line_integrals"}))
      ->capture_default_str();
  cmd->add_option("--flat", r.flat, "Flat (open-beam) frame(s); several are averaged");
  cmd->add_option("--dark", r.dark, "Dark (offset) frame(s); several are averaged");
  cmd->add_option("--detector", a.detector,
                  "Columns and rows of the image the geometry describes (default: the first projection file's size)")
      ->expected(2)
      ->check(positive_number);
  auto* pitch =
      cmd->add_option("--pitch", r.pitch_mm, "Pixel pitch in mm: one value or u v")->expected(1, 2)->check(positive_number);
  if (pitch_required) pitch->required();
  add_bin_option(cmd, r.bin);
}

void add_sense_option(CLI::App* cmd, int& sense, const char* what) {
  cmd->add_option("--sense", sense, what)->check(CLI::IsMember({1, -1}))->capture_default_str();
}

}  // namespace

// NOLINTNEXTLINE(readability-function-size): one statement per option, in the order --help lists them
void register_import(CLI::App& app) {
  CLI::App* cmd = app.add_subcommand("import", "Turn a scan described elsewhere into ctk-scan/1 with per-view matrices");
  cmd->require_subcommand(1);

  struct Circular {
    CircularImportRequest request;
    PlainArguments arguments;
  };
  auto c = std::make_shared<Circular>();
  CLI::App* circular = cmd->add_subcommand(
      "circular",
      "A circular orbit: view k at angle first + k step; volume frame with the rotation axis on +z; at t = sense * angle the "
      "source is at SOD (sin t, cos t, 0), columns run along (cos t, -sin t, 0), rows along -z");
  add_projection_options(circular, c->request, c->arguments, true);
  circular->add_option("--sod", c->request.sod_mm, "Source to rotation axis, mm")->required()->check(positive_number);
  circular->add_option("--sdd", c->request.sdd_mm, "Source to detector, mm")->required()->check(positive_number);
  circular->add_option("--first-angle", c->request.first_angle_deg, "Angle of view 0, degrees")->capture_default_str();
  circular->add_option("--step", c->request.step_deg, "Angle between views, degrees")->required();
  circular
      ->add_option("--principal-point", c->arguments.principal_point,
                   "u0 v0 in pixels: where the central ray meets the detector (u0 is also the rotation axis' column); default: "
                   "the detector centre")
      ->expected(2);
  add_sense_option(circular, c->request.sense, "Rotation sense, +1 or -1");
  circular->callback([c] {
    with_arguments(c->request, c->arguments).principal_point_px = principal_point(c->arguments.principal_point);
    print(run_import(c->request));
  });

  struct ConeVec {
    ConeVecImportRequest request;
    PlainArguments arguments;
    std::string orientation = "as-described";
  };
  auto v = std::make_shared<ConeVec>();
  CLI::App* cone_vec =
      cmd->add_subcommand("cone-vec", "ASTRA cone_vec rows (source, detector centre, column step, row step), mm");
  add_projection_options(cone_vec, v->request, v->arguments, false);
  cone_vec->add_option("--vectors", v->request.vectors, "Text file, 12 numbers per line")->required()->check(CLI::ExistingFile);
  cone_vec->add_option("--vector-rows", v->request.vector_rows,
                       "Row of the vectors file for each projection, in view order (default: 0, 1, ...)");
  cone_vec
      ->add_option("--orientation", v->orientation,
                   "How the stored files relate to the image the vectors describe: as-described, or transpose-flipud "
                   "(described = transpose(flipud(stored)), as the CWI walnut loader does)")
      ->check(CLI::IsMember({"as-described", "transpose-flipud"}))
      ->capture_default_str();
  cone_vec->callback([v] {
    with_arguments(v->request, v->arguments).orientation = stored_orientation_from_string(v->orientation);
    print(run_import(v->request));
  });

  struct Rtk {
    RtkImportRequest request;
    PlainArguments arguments;
    std::string rows;  // empty: what the file's ctk comment names, else as-stored
  };
  auto r = std::make_shared<Rtk>();
  CLI::App* rtk =
      cmd->add_subcommand("rtk",
                          "RTK's geometry XML, one <Projection> per file; RTK's detector coordinates (mm) become pixels by "
                          "u = (cols - 1) / 2 + x / pitch_u, v = (rows - 1) / 2 - y / pitch_v (RTK's y runs up the stored rows)");
  add_projection_options(rtk, r->request, r->arguments, true);
  rtk->add_option("--geometry", r->request.geometry, "RTK geometry XML (RTKThreeDCircularGeometry, version 2 or 3)")
      ->required()
      ->check(CLI::ExistingFile);
  rtk->add_option("--rows", r->rows,
                  "as-stored: RTK indexed the images as stored (y = (v - (rows - 1) / 2) pitch); flipped: flipped vertically "
                  "(y = ((rows - 1) / 2 - v) pitch); default: what a file written by ctk names, else as-stored")
      ->check(CLI::IsMember({"as-stored", "flipped"}));
  rtk->callback([r] {
    with_arguments(r->request, r->arguments);
    if (!r->rows.empty()) r->request.rows = rtk_rows_from_string(r->rows);
    print(run_import(r->request));
  });

  struct NxTomo {
    NxTomoImportRequest request;
    PlainArguments arguments;
    std::vector<double> pitch;
  };
  auto n = std::make_shared<NxTomo>();
  CLI::App* nxtomo = cmd->add_subcommand(
      "nxtomo",
      "An HDF5/NeXus NXtomo file: projections, flats and darks by image key, a circular orbit from the rotation angles; "
      "the frames are copied out as TIFF into <out stem>.frames/. NeXus' frame: the sample turns right-handed about the "
      "vertical by the angle, columns run along +x (to the left looking downstream), row 0 at the top");
  nxtomo->add_option("--nexus", n->request.nexus, "The NXtomo file (.nx, .nxs, .h5)")->required()->check(CLI::ExistingFile);
  add_out_option(nxtomo, n->request);
  nxtomo->add_option("--entry", n->request.entry, "The NXentry to read (default: the first whose definition is NXtomo)");
  nxtomo
      ->add_option("--sod", n->request.setup.source_to_axis_mm,
                   "Source to rotation axis, mm (default: |instrument/source/distance|)")
      ->check(positive_number);
  nxtomo
      ->add_option("--sdd", n->request.setup.source_to_detector_mm,
                   "Source to detector, mm (default: SOD + instrument/detector/distance)")
      ->check(positive_number);
  nxtomo->add_option("--pitch", n->pitch, "Pixel pitch in mm: one value or u v (default: the detector's x/y_pixel_size)")
      ->expected(1, 2)
      ->check(positive_number);
  nxtomo->add_option("--principal-point", n->arguments.principal_point, "u0 v0 in pixels (default: the detector centre)")
      ->expected(2);
  add_sense_option(nxtomo, n->request.setup.sense, "Rotation sense, +1 or -1");
  nxtomo->add_option("--kind", n->arguments.kind, "counts (normalised by the flat and dark frames) or line_integrals")
      ->check(CLI::IsMember({"counts", "line_integrals"}))
      ->capture_default_str();
  add_bin_option(nxtomo, n->request.bin);
  nxtomo->callback([n] {
    NxTomoSetup& setup = n->request.setup;
    if (!n->pitch.empty()) setup.pitch_mm = Eigen::Vector2d(n->pitch.front(), n->pitch.back());
    setup.principal_point_px = principal_point(n->arguments.principal_point);
    setup.line_integrals = n->arguments.kind == "line_integrals";
    // Ctrl-C while the frames are copied: stopped between two, nothing left behind, exit 130.
    const InterruptionWatch watch;
    print(run_import(n->request, [](int written, int total) {
      if (written == total || written % 50 == 0)
        std::cout << "\r  frames " << written << " of " << total << (written == total ? "\n" : "") << std::flush;
      if (InterruptionWatch::requested())
        throw Interrupted("import stopped on request after " + std::to_string(written) + " of " + std::to_string(total) +
                          " frames; nothing written");
    }));
  });

  auto k = std::make_shared<NikonImportRequest>();
  CLI::App* nikon = cmd->add_subcommand(
      "nikon",
      "A Nikon (X-Tek) scan: its .xtekct file and the <Name>_NNNN.tif projections beside it, placed as CIL's reader "
      "documents (axis offset, tilt and roll included), counts normalised by the white level");
  nikon->add_option("--xtekct", k->xtekct, "The .xtekct file")->required()->check(CLI::ExistingFile);
  add_out_option(nikon, *k);
  add_sense_option(nikon, k->sense, "+1 as the file states, -1 the sample turning the other way");
  add_bin_option(nikon, k->bin);
  nikon->callback([k] { print(run_import(*k)); });
}

}  // namespace ctk::tools

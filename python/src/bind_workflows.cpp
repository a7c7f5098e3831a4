// The workflows a lab runs from Python with the same library entry points as the command line:
// a simulated scan, a circular scan imported from its numbers, calibration, diagnosis,
// reconstruction and the markerless loop.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include <cmath>
#include <filesystem>
#include <functional>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "bindings.hpp"
#include "conversions.hpp"
#include "ctk/calib/calibration_pictures.hpp"
#include "ctk/calib/calibration_run.hpp"
#include "ctk/calib/diagnosis_pictures.hpp"
#include "ctk/calib/diagnosis_run.hpp"
#include "ctk/calib/holder_measurement.hpp"
#include "ctk/calib/holder_pictures.hpp"
#include "ctk/core/html_report.hpp"
#include "ctk/geom/import_run.hpp"
#include "ctk/geom/nominal_geometry.hpp"
#include "ctk/phantoms/simulation_run.hpp"
#include "ctk/recon/reconstruction_run.hpp"
#include "ctk/recon/refine_scan.hpp"
#include "ctk/recon/refinement_pictures.hpp"
#include "interruptible.hpp"
#include "numpy_arrays.hpp"
#include "python_bridge.hpp"

namespace ctk::python {

namespace {

namespace fs = std::filesystem;

py::array_t<double> circular(const std::vector<double>& angles_deg, const std::array<int, 2>& detector_shape,
                             const std::array<double, 2>& pixel_mm, double sod, double sdd,
                             const std::optional<std::array<double, 2>>& pp, int sense) {
  CircularOrbit orbit;
  orbit.detector = {detector_shape[1], detector_shape[0], pixel_mm[0], pixel_mm[1]};
  orbit.principal_point_px = pp ? Eigen::Vector2d((*pp)[0], (*pp)[1]) : orbit.detector.centre_px();
  orbit.source_to_axis_mm = sod;
  orbit.source_to_detector_mm = sdd;
  orbit.sense = sense;
  for (double a : angles_deg) orbit.angles_rad.push_back(a * M_PI / 180.0);
  return matrices_to_numpy(circular_matrices(orbit));
}

// The scan an import wrote, as read back; its warnings (missing projection files, keys not
// modelled) go to Python's warnings.
py::object imported_scan(const ImportRun& run) {
  const py::object warn = py::module_::import("warnings").attr("warn");
  for (const std::string& w : run.warnings) warn(w, py::handle(PyExc_UserWarning), 2);
  return to_python(scan_to_json(run.scan));
}

// A workflow's request field named as this module's keyword (`renamed`: those that differ).
std::function<std::string(const std::string&)> keywords(std::map<std::string, std::string> renamed) {
  return [renamed = std::move(renamed)](const std::string& field) {
    const auto k = renamed.find(field);
    return k != renamed.end() ? k->second : field;
  };
}

py::object import_nxtomo(const fs::path& nexus, const fs::path& out, const std::string& entry, std::optional<double> sod,
                         std::optional<double> sdd, const std::optional<std::array<double, 2>>& pixel_mm,
                         const std::optional<std::array<double, 2>>& principal_point, int sense, const std::string& kind, int bin,
                         const py::object& progress) {
  if (kind != "counts" && kind != "line_integrals") throw py::value_error("kind: expected counts or line_integrals, got " + kind);
  NxTomoImportRequest r;
  r.field_names = keywords({{"setup.source_to_axis_mm", "sod"},
                            {"setup.source_to_detector_mm", "sdd"},
                            {"setup.pitch_mm", "pixel_mm"},
                            {"setup.principal_point_px", "principal_point"},
                            {"setup.sense", "sense"}});
  r.nexus = nexus;
  r.out = out;
  r.entry = entry;
  r.bin = bin;
  r.setup.source_to_axis_mm = sod;
  r.setup.source_to_detector_mm = sdd;
  if (pixel_mm) r.setup.pitch_mm = Eigen::Vector2d((*pixel_mm)[0], (*pixel_mm)[1]);
  if (principal_point) r.setup.principal_point_px = Eigen::Vector2d((*principal_point)[0], (*principal_point)[1]);
  r.setup.sense = sense;
  r.setup.line_integrals = kind == "line_integrals";
  // Copying the frames stops on Ctrl-C or a progress callable raising: its outputs are then removed.
  PythonBridge bridge;
  const auto copied = [&, report = bridge.progress(progress)](int written, int total) {
    report(written, total);
    bridge.end_run_if_stopping();
  };
  std::optional<ImportRun> run;
  bridge.run_stoppable([&] { run = run_import(r, copied); });
  return imported_scan(*run);
}

py::object import_nikon(const fs::path& xtekct, const fs::path& out, int sense, int bin) {
  NikonImportRequest r;
  r.field_names = keywords({});
  r.xtekct = xtekct;
  r.out = out;
  r.sense = sense;
  r.bin = bin;
  return imported_scan(interruptible([&] { return run_import(r); }));
}

py::object import_scan(const fs::path& out, const DoubleArray& matrices, const std::vector<fs::path>& files,
                       const std::array<int, 2>& detector_shape, const std::array<double, 2>& pixel_mm,
                       const std::vector<fs::path>& flat, const std::vector<fs::path>& dark) {
  if (flat.empty() != dark.empty()) throw py::value_error("raw counts need both flat and dark (line integrals neither)");
  MatricesImportRequest r;
  r.field_names = keywords({{"detector", "detector_shape"}, {"pitch_mm", "pixel_mm"}});
  r.out = out;
  r.matrices = matrices_from_numpy(matrices, static_cast<py::ssize_t>(files.size()));
  for (const fs::path& f : files) r.files.push_back(fs::absolute(f).string());
  r.kind = flat.empty() ? ProjectionKind::line_integrals : ProjectionKind::counts;
  for (const fs::path& f : flat) r.flat.push_back(fs::absolute(f).string());
  for (const fs::path& d : dark) r.dark.push_back(fs::absolute(d).string());
  r.detector = std::array<int, 2>{detector_shape[1], detector_shape[0]};
  r.pitch_mm = {pixel_mm[0], pixel_mm[1]};
  return imported_scan(run_import(r));
}

// The pictures a command writes beside its outputs, named in `report["pictures"]` (file names
// beside `stem`), and its HTML page: their paths under "pictures" and "page".
void add_pictures_and_page(py::dict& d, const std::string& command, const std::string& brief, nlohmann::json report,
                           const std::vector<std::string>& names, const fs::path& stem, const fs::path& page) {
  const std::vector<fs::path> files = pictures_beside(stem, names);
  report["pictures"] = names;
  write_run_page(command, brief, report, files, page);
  std::vector<std::string> paths;
  paths.reserve(files.size());
  for (const fs::path& f : files) paths.push_back(f.string());
  d["pictures"] = paths;
  d["page"] = page.string();
}

py::dict refine(const fs::path& scan_file, const std::optional<fs::path>& geometry_file, const std::vector<std::string>& effects,
                double coarsening, double blur_arc_deg, double z, const py::object& log,
                const std::optional<fs::path>& pictures) {
  RefineScanOptions o;
  o.effects = effects;
  o.coarsening = coarsening;
  o.blur_arc_deg = blur_arc_deg;
  o.z_accept = z;
  o.validate();
  const ScanDescription scan = read_scan(scan_file);
  const Geometry geometry = geometry_or_nominal(scan, scan_file, geometry_file.value_or(fs::path()));
  // The loop has no stop request of its own: a step's log line that finds the run stopping ends it.
  PythonBridge bridge;
  const auto say = [&, line_to = bridge.log(log)](const std::string& line) {
    line_to(line);
    bridge.end_run_if_stopping();
  };
  std::optional<RefineScanSummary> s;
  bridge.run_stoppable([&] { s = refine_scan(scan, geometry, o, say); });
  py::dict d;
  const nlohmann::json report = s->report();
  d["report"] = to_python(report);
  d["geometry"] = to_python(geometry_to_json(s->refined));
  d["brief"] = s->brief();
  std::vector<ProjectionMatrix> ok;
  for (int i : s->refined.ok_views()) ok.push_back(*s->refined.views[static_cast<std::size_t>(i)].P);
  d["matrices"] = matrices_to_numpy(ok);
  if (pictures)
    add_pictures_and_page(d, "refine", s->brief(), report, write_refinement_pictures(s->result, *pictures), *pictures,
                          pictures->string() + ".html");
  auto slice = [](Volume v) {  // the central axial slice, (y, x)
    const auto s3 = volume_shape(v.layout);
    auto owner = std::make_unique<Volume>(std::move(v));
    float* data = owner->data.data() + static_cast<std::size_t>(s3[0] / 2) * static_cast<std::size_t>(s3[1] * s3[2]);
    return owning_array(std::move(owner), data, {s3[1], s3[2]});
  };
  d["slice_before"] = slice(std::move(s->result.volume_before));
  d["slice_after"] = slice(std::move(s->result.volume_after));
  return d;
}

py::dict calibrate(const fs::path& scan_file, int min_spheres, double max_rms_px, double search_px, bool image_only,
                   const py::object& progress, const std::optional<fs::path>& pictures) {
  CalibrationRunOptions o;
  o.calibration.min_spheres = min_spheres;
  o.calibration.max_rms_px = max_rms_px;
  o.calibration.search_px = search_px;
  o.calibration.validate();
  o.image_only = image_only;
  const ScanDescription scan = read_scan(scan_file);
  PythonBridge bridge;
  BatchControl control;
  control.stop_requested = [&] { return bridge.stop_requested(); };
  std::optional<CalibrationRun> run;
  interruptible([&] { run = run_calibration(scan, o, bridge.progress(progress), &control); });
  bridge.raise_if_stopped();
  py::dict d;
  d["geometry"] = to_python(geometry_to_json(run->calibration.geometry));
  const nlohmann::json report = run->report();
  d["report"] = to_python(report);
  d["brief"] = run->brief() + "\n" + run->wall_and_prior();
  if (pictures)
    add_pictures_and_page(d, "calibrate", run->brief(), report,
                          write_calibration_pictures(scan, run->calibration, o.calibration.max_rms_px, *pictures), *pictures,
                          pictures->string() + ".report.html");
  return d;
}

py::dict diagnose(const fs::path& scan_file, const fs::path& geometry_file, const std::optional<double>& repeatability_mm,
                  const std::optional<double>& repeatability_deg, const py::object& log,
                  const std::optional<fs::path>& pictures) {
  DiagnosisRunOptions o;
  o.repeatability_mm = repeatability_mm;
  o.repeatability_deg = repeatability_deg;
  o.diagnosis.validate();
  const ScanDescription scan = read_scan(scan_file);
  const Geometry geometry = geometry_for_scan(scan, read_geometry(geometry_file));
  PythonBridge bridge;
  std::optional<DiagnosisRun> run;
  interruptible([&] { run = run_diagnosis(scan, geometry, o, {}, bridge.log(log)); });
  bridge.raise_if_stopped();
  py::dict d;
  const nlohmann::json report = run->report();
  d["report"] = to_python(report);
  d["corrected_scan"] = to_python(scan_to_json(run->corrected));
  d["brief"] = run->brief();
  if (pictures)
    add_pictures_and_page(d, "diagnose", run->brief(), report,
                          write_diagnosis_pictures(run->diagnosis, run->observations, *pictures), *pictures,
                          pictures->string() + ".html");
  return d;
}

py::dict measure_holder(const fs::path& scan_file, const fs::path& geometry_file, int min_views, const py::object& log,
                        const std::optional<fs::path>& pictures) {
  HolderMeasurementOptions o;
  o.min_views = min_views;
  o.validate();
  const ScanDescription scan = read_scan(scan_file);
  const Geometry geometry = geometry_for_scan(scan, read_geometry(geometry_file));
  PythonBridge bridge;
  std::optional<HolderMeasurement> run;
  interruptible([&] { run = run_holder_measurement(scan, geometry, o, {}, bridge.log(log)); });
  bridge.raise_if_stopped();
  py::dict d;
  const nlohmann::json holder = run->holder_file(scan_file.string());
  d["holder"] = to_python(holder);
  d["brief"] = run->brief();
  if (pictures)
    add_pictures_and_page(d, "holder measure", run->brief(), holder, write_holder_pictures(*run, *pictures), *pictures,
                          pictures->string() + ".html");
  return d;
}

// The library's defaults under simulate()'s keywords (a test checks the signature against them).
py::dict simulation_defaults() {
  const SimulationRequest r;
  py::dict d;
  d["phantoms"] = py::tuple(py::cast(r.phantoms));
  d["holder"] = r.holder;
  d["trajectory"] = r.trajectory;
  d["views"] = r.views;
  d["nside"] = r.nside;
  d["cap_deg"] = py::make_tuple(r.cap_min_deg, r.cap_max_deg);
  d["detector_shape"] = py::make_tuple(r.rows, r.cols);
  d["pitch_mm"] = r.pitch_mm;
  d["sdd_mm"] = r.sdd_mm;
  d["sod_mm"] = r.sod_mm;
  d["supersampling"] = r.supersampling;
  d["flat_counts"] = r.counts.flat_counts;
  d["dark_counts"] = r.counts.dark_counts;
  d["filter_al_mm"] = r.filter_al_mm;
  d["robot_noise_mm"] = r.robot_noise.translation_mm;
  d["robot_noise_deg"] = r.robot_noise.rotation_deg;
  d["seed"] = r.seed;
  return d;
}

// The library's defaults under reconstruct()'s keywords (a test checks the signature against them).
py::dict reconstruction_defaults() {
  const ReconstructionOptions o;
  py::dict d;
  d["method"] = to_string(o.method);
  d["iterations"] = o.iterations;
  d["subsets"] = o.subsets;
  d["lambda_"] = o.lambda;
  d["regulariser"] = to_string(o.regulariser);
  d["huber_delta"] = o.huber_delta;
  d["tolerance"] = o.tolerance;
  d["preconditioner"] = to_string(o.preconditioner);
  d["weighted"] = o.statistical_weights;
  d["undistort"] = o.undistort;
  d["voxel_mm"] = o.voxel_mm;
  return d;
}

py::dict reconstruct(const fs::path& scan_file, const std::optional<fs::path>& geometry_file, const std::string& method,
                     int iterations, int held_out_every, int subsets, double lambda, const std::string& regulariser,
                     double huber_delta, double tolerance, const std::string& preconditioner, bool weighted, bool undistort,
                     const std::optional<std::array<int, 3>>& size, double voxel_mm, const py::object& progress) {
  ReconstructionOptions o;
  o.method = reconstruction_method(method);  // std::invalid_argument (ValueError) naming the others
  o.subsets = subsets;
  o.iterations = iterations;
  if (held_out_every >= 0) o.held_out_every = held_out_every;  // -1: the library's default
  o.lambda = lambda;
  o.regulariser = regulariser_from_string(regulariser);
  o.huber_delta = huber_delta;
  o.tolerance = tolerance;
  o.preconditioner = cg_preconditioner_from_string(preconditioner);
  o.statistical_weights = weighted;
  o.undistort = undistort;
  if (size) {  // (z, y, x) as numpy orders a volume
    o.size = {(*size)[2], (*size)[1], (*size)[0]};
  }
  o.voxel_mm = voxel_mm;
  o.validate();
  const ScanDescription scan = read_scan(scan_file);
  const Geometry geometry = geometry_or_nominal(scan, scan_file, geometry_file.value_or(fs::path()));
  PythonBridge bridge;
  ReconstructionHooks hooks;
  hooks.reading = bridge.progress(progress);
  hooks.iterating = bridge.progress(progress);
  hooks.stop_requested = [&] { return bridge.stop_requested(); };
  std::optional<ReconstructionRun> run;
  interruptible([&] { run = run_reconstruction(scan, geometry, o, hooks); });
  bridge.raise_if_stopped();
  py::dict d;
  d["report"] = to_python(run->report());
  d["brief"] = run->brief();
  const VolumeLayout layout = run->volume.layout;
  d["voxel_mm"] = layout.voxel_mm.x();
  d["origin_mm"] = std::array<double, 3>{layout.origin_mm.x(), layout.origin_mm.y(), layout.origin_mm.z()};
  d["volume"] = to_numpy(std::move(run->volume));
  return d;
}

py::dict simulate(const fs::path& out, const std::vector<std::string>& phantoms, const std::string& holder,
                  const std::string& trajectory, int views, int nside, const std::array<double, 2>& cap_deg,
                  const std::optional<fs::path>& poses, const std::array<int, 2>& detector_shape, double pitch_mm, double sdd_mm,
                  double sod_mm, int supersampling, const std::string& output, double flat_counts, double dark_counts,
                  const std::optional<double>& kvp, double filter_al_mm, double robot_noise_mm, double robot_noise_deg,
                  std::uint64_t seed, const py::object& effects, const py::object& progress, const py::object& log) {
  if (output != "counts" && output != "line-integrals")
    throw py::value_error("output must be 'counts' or 'line-integrals', not '" + output + "'");
  SimulationRequest r;
  r.phantoms = phantoms;
  r.holder = holder;
  r.trajectory = trajectory;
  r.views = views;
  r.nside = nside;
  r.cap_min_deg = cap_deg[0];
  r.cap_max_deg = cap_deg[1];
  if (poses) r.poses = *poses;
  r.rows = detector_shape[0];
  r.cols = detector_shape[1];
  r.pitch_mm = pitch_mm;
  r.sdd_mm = sdd_mm;
  r.sod_mm = sod_mm;
  r.supersampling = supersampling;
  r.output = output == "counts" ? SimulatedOutput::counts : SimulatedOutput::line_integrals;
  r.counts = {flat_counts, dark_counts};
  r.kvp = kvp;
  r.filter_al_mm = filter_al_mm;
  r.robot_noise = {robot_noise_mm, robot_noise_deg};
  r.seed = seed;
  r.validate();
  r.effects = simulation_effects_from_json(effects.is_none() ? nlohmann::json::object() : from_python(effects),
                                           Detector{r.cols, r.rows, pitch_mm, pitch_mm});
  PythonBridge bridge;
  std::optional<SimulationRun> run;
  interruptible([&] { run = run_simulation(r, out, bridge.progress(progress), bridge.log(log)); });
  bridge.raise_if_stopped();
  py::dict d;
  d["scan_file"] = run->scan_file;
  d["brief"] = run->brief();
  d["saturated_pixels"] = run->report.saturated_pixels;
  return d;
}

}  // namespace

void bind_workflows(py::module_& m) {
  m.def("_calibrate", &calibrate, py::arg("scan"), py::arg("min_spheres"), py::arg("max_rms_px"), py::arg("search_px"),
        py::arg("image_only"), py::arg("progress"), py::arg("pictures"));
  m.def("_diagnose", &diagnose, py::arg("scan"), py::arg("geometry"), py::arg("repeatability_mm"), py::arg("repeatability_deg"),
        py::arg("log"), py::arg("pictures"));
  m.def("circular_matrices", &circular, py::arg("angles_deg"), py::arg("detector_shape"), py::arg("pixel_mm"), py::arg("sod"),
        py::arg("sdd"), py::arg("principal_point") = py::none(), py::arg("sense") = 1, R"doc(
A circular orbit by its numbers as (views, 3, 4) matrices: rotation axis +z through the origin, the
source of view k at SOD (sin t, cos t, 0) with t = sense * angle_k, columns along (cos t, -sin t, 0),
rows along -z; the axis projects onto the principal point's column (default: the detector centre).
detector_shape (rows, cols), pixel_mm (u, v).
)doc");
  m.def("import_scan", &import_scan, py::arg("out"), py::arg("matrices"), py::arg("files"), py::arg("detector_shape"),
        py::arg("pixel_mm"), py::arg("flat") = std::vector<fs::path>{}, py::arg("dark") = std::vector<fs::path>{}, R"doc(
Writes a ctk-scan/1 file `out` (and its matrices beside it, <stem>.matrices.json) for projection
files with one matrix each; raw counts when flat and dark frames are given, line integrals
otherwise, as `ctk import` writes it (import_run.hpp). Refuses (InputError, nothing written) an `out`
that is one of the inputs, files none (or most) of which exist, and a first image whose size is not
`detector_shape`. Returns the scan as read back.
)doc");
  m.def("import_nxtomo", &import_nxtomo, py::arg("nexus"), py::arg("out"), py::arg("entry") = "", py::arg("sod") = py::none(),
        py::arg("sdd") = py::none(), py::arg("pixel_mm") = py::none(), py::arg("principal_point") = py::none(),
        py::arg("sense") = 1, py::arg("kind") = "counts", py::arg("bin") = 1, py::arg("progress") = py::none(), R"doc(
An HDF5/NeXus NXtomo file as a ctk-scan/1 file `out`, as `ctk import nxtomo` makes it: projections,
flats and darks by image key, a circular orbit from the rotation angles, the distances and pixel
size from the file unless given (sod, sdd in mm; pixel_mm (u, v); principal_point (u0, v0) px);
kind "line_integrals" for frames that are already; bin n x n recorded in the scan. The frames are
copied out as TIFF into <out stem>.frames/; progress(written, total) as they are, and Ctrl-C or a
raising progress stops the copy with nothing left behind. Returns the scan as read back; missing
or assumed numbers are InputError naming the keyword.
)doc");
  m.def("import_nikon", &import_nikon, py::arg("xtekct"), py::arg("out"), py::arg("sense") = 1, py::arg("bin") = 1, R"doc(
A Nikon (X-Tek) scan, its .xtekct file and the <Name>_NNNN.tif projections beside it, as a
ctk-scan/1 file `out`, as `ctk import nikon` makes it (the white level and a zero dark written as
images beside it). Returns the scan as read back; keys read and not modelled are warned about.
)doc");
  m.def("_simulate", &simulate, py::arg("out"), py::arg("phantoms"), py::arg("holder"), py::arg("trajectory"), py::arg("views"),
        py::arg("nside"), py::arg("cap_deg"), py::arg("poses"), py::arg("detector_shape"), py::arg("pitch_mm"), py::arg("sdd_mm"),
        py::arg("sod_mm"), py::arg("supersampling"), py::arg("output"), py::arg("flat_counts"), py::arg("dark_counts"),
        py::arg("kvp"), py::arg("filter_al_mm"), py::arg("robot_noise_mm"), py::arg("robot_noise_deg"), py::arg("seed"),
        py::arg("effects"), py::arg("progress"), py::arg("log"));
  m.def("_measure_holder", &measure_holder, py::arg("scan"), py::arg("geometry"), py::arg("min_views"), py::arg("log"),
        py::arg("pictures"));
  m.def("_reconstruction_defaults", &reconstruction_defaults);
  m.def("_simulation_defaults", &simulation_defaults);
  m.def("_reconstruct", &reconstruct, py::arg("scan"), py::arg("geometry"), py::arg("method"), py::arg("iterations"),
        py::arg("held_out_every"), py::arg("subsets"), py::arg("lambda_"), py::arg("regulariser"), py::arg("huber_delta"),
        py::arg("tolerance"), py::arg("preconditioner"), py::arg("weighted"), py::arg("undistort"), py::arg("size"),
        py::arg("voxel_mm"), py::arg("progress"));
  m.def("_refine", &refine, py::arg("scan"), py::arg("geometry"), py::arg("effects"), py::arg("coarsening"),
        py::arg("blur_arc_deg"), py::arg("z"), py::arg("log"), py::arg("pictures"));
}

}  // namespace ctk::python

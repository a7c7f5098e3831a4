// The files of the toolkit as Python objects: scan and geometry documents as dicts (checked as the
// command line checks them, written atomically), matrices as (views, 3, 4) arrays, ASTRA cone_vec
// rows as (views, 12) arrays, volume files as (z, y, x) float32 arrays with their voxel size and origin.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include <filesystem>
#include <stdexcept>
#include <string>
#include <vector>

#include "bindings.hpp"
#include "conversions.hpp"
#include "ctk/core/nexus_tomo.hpp"
#include "ctk/core/volume_file.hpp"
#include "ctk/geom/astra.hpp"
#include "ctk/geom/geometry_file.hpp"
#include "ctk/geom/nikon_xtekct.hpp"
#include "ctk/geom/rtk_geometry.hpp"
#include "ctk/geom/scan.hpp"
#include "interruptible.hpp"
#include "numpy_arrays.hpp"

namespace ctk::python {

namespace {

namespace fs = std::filesystem;

Detector detector_from(const std::array<int, 2>& shape, const std::array<double, 2>& pitch_mm) {
  if (shape[0] < 1 || shape[1] < 1) throw py::value_error("detector_shape needs two positive sizes (rows, cols)");
  if (!(pitch_mm[0] > 0 && pitch_mm[1] > 0)) throw py::value_error("pixel_mm needs two positive pitches (u, v)");
  return {shape[1], shape[0], pitch_mm[0], pitch_mm[1]};
}

py::array_t<double> matrices_from_cone_vec(const DoubleArray& vecs, const std::array<int, 2>& detector_shape,
                                           const std::array<double, 2>& pixel_mm, double mm_per_unit) {
  if (vecs.ndim() != 2 || vecs.shape(1) != 12)
    throw py::value_error("cone_vec rows have shape " + shape_text(vecs) + ", expected (views, 12)");
  const Detector d = detector_from(detector_shape, pixel_mm);
  std::vector<ProjectionMatrix> out;
  for (py::ssize_t v = 0; v < vecs.shape(0); ++v) {
    ConeVec c{};
    for (int i = 0; i < 12; ++i) c[static_cast<std::size_t>(i)] = vecs.at(v, i);
    out.push_back(from_cone_vec(c, d, mm_per_unit));
  }
  return matrices_to_numpy(out);
}

py::array_t<double> cone_vec_from_matrices(const DoubleArray& matrices, const std::array<int, 2>& detector_shape,
                                           const std::array<double, 2>& pixel_mm, double mm_per_unit) {
  const std::vector<ProjectionMatrix> P = matrices_from_numpy(matrices);
  const Detector d = detector_from(detector_shape, pixel_mm);
  py::array_t<double> out(std::vector<py::ssize_t>{static_cast<py::ssize_t>(P.size()), 12});
  auto w = out.mutable_unchecked<2>();
  for (py::ssize_t v = 0; v < static_cast<py::ssize_t>(P.size()); ++v) {
    const ConeVec c = to_cone_vec(P[static_cast<std::size_t>(v)], d, mm_per_unit);
    for (int i = 0; i < 12; ++i) w(v, i) = c[static_cast<std::size_t>(i)];
  }
  return out;
}

RtkRows rows_from(const std::string& rows) {
  try {
    return rtk_rows_from_string(rows);
  } catch (const std::invalid_argument& e) {
    throw py::value_error(std::string("rows: ") + e.what());
  }
}

py::array_t<double> read_rtk(const fs::path& file, const std::array<int, 2>& detector_shape,
                             const std::array<double, 2>& pixel_mm, const std::string& rows) {
  const Detector d = detector_from(detector_shape, pixel_mm);
  const RtkGeometry g = read_rtk_geometry(file);
  const RtkRows sense = rows.empty() ? g.pixel_map() : rows_from(rows);
  return matrices_to_numpy(holder_matrices(g, d, sense));
}

py::object optional_mm(const std::optional<double>& v) { return v ? py::object(py::float_(*v)) : py::object(py::none()); }

// Every frame as (frames, rows, cols) float32, read with the GIL released, and what the file says.
py::dict read_nxtomo_file(const fs::path& file, const std::string& entry) {
  const NxTomo scan = read_nxtomo(file, entry);
  py::array_t<float> frames(std::vector<py::ssize_t>{scan.frames, scan.rows, scan.cols});
  float* out = frames.mutable_data();
  interruptible([&] {
    const std::size_t size = static_cast<std::size_t>(scan.rows) * static_cast<std::size_t>(scan.cols);
    const NxTomoFrames reader(scan);
    for (int f = 0; f < scan.frames; ++f) {
      throw_if_stop_requested();
      const Image image = reader.read(f);
      std::copy(image.pixels.begin(), image.pixels.end(), out + static_cast<std::size_t>(f) * size);
    }
  });
  py::array_t<int> keys(static_cast<py::ssize_t>(scan.frames));
  for (int f = 0; f < scan.frames; ++f) keys.mutable_at(f) = static_cast<int>(scan.kind[static_cast<std::size_t>(f)]);
  py::dict d;
  d["entry"] = scan.entry;
  d["frames"] = frames;
  d["image_key"] = keys;
  d["rotation_angle_deg"] =
      py::array_t<double>(static_cast<py::ssize_t>(scan.rotation_angle_deg.size()), scan.rotation_angle_deg.data());
  d["x_pixel_size_mm"] = optional_mm(scan.x_pixel_size_mm);
  d["y_pixel_size_mm"] = optional_mm(scan.y_pixel_size_mm);
  d["sample_to_detector_mm"] = optional_mm(scan.sample_to_detector_mm);
  d["source_to_sample_mm"] = optional_mm(scan.source_to_sample_mm);
  d["warnings"] = scan.warnings;
  return d;
}

py::dict read_xtekct_file(const fs::path& file, int sense) {
  const NikonScan scan = read_xtekct(file);
  if (sense != 1 && sense != -1) throw py::value_error("sense: expected +1 or -1");
  std::vector<std::string> files;
  for (const fs::path& f : nikon_projection_files(scan)) files.push_back(f.string());
  py::dict d;
  d["matrices"] = matrices_to_numpy(nikon_matrices(scan, sense));
  d["files"] = files;
  d["detector_shape"] = py::make_tuple(scan.detector.rows, scan.detector.cols);
  d["pixel_mm"] = py::make_tuple(scan.detector.pitch_u_mm, scan.detector.pitch_v_mm);
  d["white_level"] = scan.white_level;
  d["source_to_object_mm"] = scan.source_to_object_mm;
  d["source_to_detector_mm"] = scan.source_to_detector_mm;
  d["warnings"] = scan.warnings;
  return d;
}

void write_rtk(const DoubleArray& matrices, const fs::path& file, const std::array<int, 2>& detector_shape,
               const std::array<double, 2>& pixel_mm, const std::string& rows) {
  const Detector d = detector_from(detector_shape, pixel_mm);
  const std::vector<ProjectionMatrix> P = matrices_from_numpy(matrices);
  if (P.empty()) throw py::value_error("matrices: no view");
  const RtkRows sense = rows.empty() ? rtk_rows_for(P.front()) : rows_from(rows);
  std::vector<RtkProjection> views;
  for (std::size_t v = 0; v < P.size(); ++v) {
    try {
      views.push_back(to_rtk(P[v], d, sense));
    } catch (const std::invalid_argument& e) {
      throw py::value_error("matrices[" + std::to_string(v) + "]: " + e.what());
    }
  }
  write_rtk_geometry(views, sense, file);
}

}  // namespace

// NOLINTNEXTLINE(readability-function-size): one binding per statement, as Python's help lists them
void bind_files(py::module_& m) {
  m.def(
      "read_volume",
      [](const fs::path& file) {
        Volume v = read_volume(file);
        const VolumeLayout l = v.layout;
        py::dict layout;
        layout["voxel_mm"] = std::array<double, 3>{l.voxel_mm.x(), l.voxel_mm.y(), l.voxel_mm.z()};
        layout["origin_mm"] = std::array<double, 3>{l.origin_mm.x(), l.origin_mm.y(), l.origin_mm.z()};
        return py::make_tuple(to_numpy(std::move(v)), layout);
      },
      py::arg("file"),
      "A volume file (.nrrd, .mha, .mhd, .tif, .h5) as (array (z, y, x) float32, {'voxel_mm': (x, y, z), 'origin_mm': "
      "(x, y, z)}); origin_mm is the centre of voxel 0 in the holder frame.");
  m.def(
      "write_volume",
      [](const FloatArray& volume, const fs::path& file, const std::array<double, 3>& voxel_mm, const py::object& origin_mm) {
        if (volume.ndim() != 3) throw py::value_error("the volume has shape " + shape_text(volume) + ", expected (z, y, x)");
        VolumeLayout l;
        l.size = {static_cast<int>(volume.shape(2)), static_cast<int>(volume.shape(1)), static_cast<int>(volume.shape(0))};
        l.voxel_mm = {voxel_mm[0], voxel_mm[1], voxel_mm[2]};
        if (!(l.voxel_mm.array() > 0).all() || !l.voxel_mm.allFinite())
          throw py::value_error("voxel_mm: expected finite sizes above 0 (mm), got (" + std::to_string(voxel_mm[0]) + ", " +
                                std::to_string(voxel_mm[1]) + ", " + std::to_string(voxel_mm[2]) + ")");
        l.origin_mm = origin_mm.is_none() ? VolumeLayout::centred(l.size, l.voxel_mm).origin_mm : [&] {
          const auto o = origin_mm.cast<std::array<double, 3>>();
          return Eigen::Vector3d(o[0], o[1], o[2]);
        }();
        Volume v(l);
        std::copy(volume.data(), volume.data() + v.data.size(), v.data.data());
        write_volume(v, file);
      },
      py::arg("volume"), py::arg("file"), py::arg("voxel_mm") = std::array<double, 3>{1, 1, 1}, py::arg("origin_mm") = py::none(),
      "Writes a (z, y, x) float32 array in the format the extension names (.nrrd, .mha, .mhd + .raw, .tif, .h5), "
      "atomically; voxel_mm and origin_mm (centre of voxel 0; default: centred on the holder origin) as (x, y, z).");
  m.def(
      "read_scan", [](const fs::path& file) { return to_python(scan_to_json(read_scan(file))); }, py::arg("file"),
      "A ctk-scan/1 file, checked (InputError naming file and key), as a dict.");
  m.def(
      "write_scan",
      [](const py::object& scan, const fs::path& file) { write_scan(scan_from_json(from_python(scan), file), file); },
      py::arg("scan"), py::arg("file"),
      "Checks a ctk-scan/1 dict as if it were at `file` (names resolve against its folder), then writes it atomically.");
  m.def(
      "read_geometry", [](const fs::path& file) { return to_python(geometry_to_json(read_geometry(file))); }, py::arg("file"),
      "A ctk-geometry/1 file, checked, as a dict (views[i]['P'] is the row-major 3x4 matrix of an ok view).");
  m.def(
      "write_geometry",
      [](const py::object& geometry, const fs::path& file) {
        write_geometry(geometry_from_json(from_python(geometry), file), file);
      },
      py::arg("geometry"), py::arg("file"), "Checks a ctk-geometry/1 dict, then writes it atomically.");
  m.def(
      "read_cone_vec",
      [](const fs::path& file) {
        const std::vector<ConeVec> rows = read_cone_vecs(file);
        py::array_t<double> out(std::vector<py::ssize_t>{static_cast<py::ssize_t>(rows.size()), 12});
        auto w = out.mutable_unchecked<2>();
        for (std::size_t v = 0; v < rows.size(); ++v)
          for (int i = 0; i < 12; ++i) w(static_cast<py::ssize_t>(v), i) = rows[v][static_cast<std::size_t>(i)];
        return out;
      },
      py::arg("file"), "ASTRA cone_vec rows (a CWI .geom text file) as a (views, 12) array.");
  m.def("matrices_from_cone_vec", &matrices_from_cone_vec, py::arg("vectors"), py::arg("detector_shape"),
        py::arg("pixel_mm") = std::array<double, 2>{1.0, 1.0}, py::arg("mm_per_unit") = 1.0,
        "ASTRA cone_vec rows (views, 12): source, detector centre, u and v pixel steps, in volume units of mm_per_unit "
        "mm) as (views, 3, 4) matrices for a detector of detector_shape (rows, cols).");
  m.def("cone_vec_from_matrices", &cone_vec_from_matrices, py::arg("matrices"), py::arg("detector_shape"),
        py::arg("pixel_mm") = std::array<double, 2>{1.0, 1.0}, py::arg("mm_per_unit") = 1.0,
        "(views, 3, 4) matrices as ASTRA cone_vec rows (views, 12), the detector placed so a column step is pixel_mm[0] long.");
  m.def("read_rtk_geometry", &read_rtk, py::arg("file"), py::arg("detector_shape"), py::arg("pixel_mm"), py::arg("rows") = "",
        "RTK's geometry XML as (views, 3, 4) matrices for a detector of detector_shape (rows, cols) and pixel_mm (u, v). "
        "rows: 'as-stored' (RTK indexed the images as stored) or 'flipped' (vertically); default: what a file written by ctk "
        "names, else 'as-stored' (docs/geometry.md). InputError names the file and the element.");
  m.def("read_nxtomo", &read_nxtomo_file, py::arg("file"), py::arg("entry") = "",
        "An HDF5/NeXus NXtomo file as a dict: frames (frames, rows, cols) float32, image_key per frame (0 projection, 1 flat, "
        "2 dark, 3 invalid), rotation_angle_deg, the pixel sizes and distances in mm (None where the file has none), "
        "entry and warnings. entry: the NXentry (default: the first whose definition is NXtomo). InputError names the "
        "file and the dataset.");
  m.def("read_xtekct", &read_xtekct_file, py::arg("file"), py::arg("sense") = 1,
        "A Nikon .xtekct scan as a dict: matrices (views, 3, 4) placed as CIL's reader documents (sense -1: the sample "
        "turning the other way), the projection files in natural order, detector_shape (rows, cols), pixel_mm (u, v), "
        "white_level, the distances and warnings. InputError names the file and the key.");
  m.def("write_rtk_geometry", &write_rtk, py::arg("matrices"), py::arg("file"), py::arg("detector_shape"), py::arg("pixel_mm"),
        py::arg("rows") = "",
        "(views, 3, 4) matrices as RTK's geometry XML (version 3), atomically, under the pixel map rows ('as-stored', "
        "'flipped'; default: the one that holds the first view, named in the file). ValueError names a matrix RTK's "
        "parameters cannot hold (skewed or non-square pixels, a detector mirrored under rows).");
}

}  // namespace ctk::python

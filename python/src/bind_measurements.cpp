// What the solvers consume, read as the command line reads it: a scan's ok views as line
// integrals, their matrices and statistical weights; and single images.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include <filesystem>
#include <memory>
#include <optional>

#include "bindings.hpp"
#include "conversions.hpp"
#include "ctk/core/image_io.hpp"
#include "ctk/geom/nominal_geometry.hpp"
#include "ctk/measure/measurements.hpp"
#include "interruptible.hpp"
#include "numpy_arrays.hpp"

namespace ctk::python {

namespace {

namespace fs = std::filesystem;

py::dict load(const fs::path& scan_file, const std::optional<fs::path>& geometry_file, bool statistical_weights, bool undistort) {
  const ScanDescription scan = read_scan(scan_file);
  const Geometry geometry = geometry_or_nominal(scan, scan_file, geometry_file.value_or(fs::path()));
  Measurements m;
  interruptible([&] { m = load_measurements(scan, geometry, {statistical_weights, undistort}); });
  py::dict d;
  d["view_indices"] = m.view_indices;
  d["matrices"] = matrices_to_numpy(m.matrices);
  d["detector_shape"] = py::make_tuple(scan.detector.rows, scan.detector.cols);
  d["pixel_mm"] = py::make_tuple(scan.detector.pitch_u_mm, scan.detector.pitch_v_mm);
  d["line_integrals"] = to_numpy(std::move(m.line_integrals));
  d["weights"] = m.weights.views > 0 ? py::object(to_numpy(std::move(m.weights))) : py::none();
  d["clamped_pixels"] = m.clamped_pixels;
  d["masked_pixels"] = m.masked_pixels;
  d["left_out"] = m.left_out;
  d["notes"] = m.notes;
  return d;
}

}  // namespace

void bind_measurements(py::module_& m) {
  m.def("_load_measurements", &load, py::arg("scan"), py::arg("geometry"), py::arg("statistical_weights"), py::arg("undistort"));
  m.def(
      "read_image",
      [](const fs::path& file) {
        Image image = read_image(file);
        auto owner = std::make_unique<std::vector<float>>(std::move(image.pixels));
        float* data = owner->data();
        return owning_array(std::move(owner), data, {image.rows, image.cols});
      },
      py::arg("file"), "One image (TIFF, EXR, ...) as float32 (rows, cols); counts stay counts.");
}

}  // namespace ctk::python

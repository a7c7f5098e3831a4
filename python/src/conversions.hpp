#pragma once
// Values that cross between C++ and Python in more than one binding: JSON documents as Python
// dicts and lists, and per-view matrices as (views, 3, 4) float64 arrays.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "ctk/geom/projection_matrix.hpp"
#include "numpy_arrays.hpp"

namespace ctk::python {

using DoubleArray = py::array_t<double, py::array::c_style | py::array::forcecast>;

inline py::object to_python(const nlohmann::json& j) { return py::module_::import("json").attr("loads")(j.dump()); }

inline nlohmann::json from_python(const py::object& o) {
  return nlohmann::json::parse(py::module_::import("json").attr("dumps")(o).cast<std::string>());
}

/// (views, 3, 4) float64, one matrix per view.
inline py::array_t<double> matrices_to_numpy(const std::vector<ProjectionMatrix>& matrices) {
  py::array_t<double> out(std::vector<py::ssize_t>{static_cast<py::ssize_t>(matrices.size()), 3, 4});
  auto w = out.mutable_unchecked<3>();
  for (std::size_t v = 0; v < matrices.size(); ++v)
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 4; ++c) w(static_cast<py::ssize_t>(v), r, c) = matrices[v].matrix()(r, c);
  return out;
}

/// Throws ValueError unless `a` is (views, 3, 4), with `views` when it is not negative.
inline std::vector<ProjectionMatrix> matrices_from_numpy(const DoubleArray& a, py::ssize_t views = -1) {
  if (a.ndim() != 3 || a.shape(1) != 3 || a.shape(2) != 4 || (views >= 0 && a.shape(0) != views))
    throw py::value_error("matrices have shape " + shape_text(a) + ", expected (" +
                          (views >= 0 ? std::to_string(views) : "views") + ", 3, 4)" + (views >= 0 ? ": one per file" : ""));
  std::vector<ProjectionMatrix> out;
  for (py::ssize_t v = 0; v < a.shape(0); ++v) {
    Matrix34d P;
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 4; ++c) P(r, c) = a.at(v, r, c);
    out.emplace_back(P);
  }
  return out;
}

}  // namespace ctk::python

// The projector as an operator: forward (volume -> projections) and adjoint, on numpy arrays read
// and written in place, the GIL released while the threads work.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <Eigen/Core>
#include <memory>
#include <vector>

#include "bindings.hpp"
#include "conversions.hpp"
#include "ctk/proj/binned_projection.hpp"
#include "ctk/proj/joseph_operator.hpp"
#include "ctk/proj/weighted_projection.hpp"
#include "interruptible.hpp"
#include "numpy_arrays.hpp"

namespace ctk::python {

namespace {

using Operator = std::shared_ptr<ProjectionOperator>;

Operator mutable_operator(const std::shared_ptr<const ProjectionOperator>& op) {
  return std::const_pointer_cast<ProjectionOperator>(op);
}

std::array<py::ssize_t, 3> stack_shape(const StackShape& s) { return {s.views, s.rows, s.cols}; }
py::tuple as_tuple(const std::array<py::ssize_t, 3>& a) { return py::make_tuple(a[0], a[1], a[2]); }

Eigen::Vector3d vector3(const py::object& o, const char* what) {
  if (py::isinstance<py::float_>(o) || py::isinstance<py::int_>(o)) return Eigen::Vector3d::Constant(o.cast<double>());
  const auto v = o.cast<std::vector<double>>();
  if (v.size() != 3) throw py::value_error(std::string(what) + " takes one number or three (x, y, z)");
  return {v[0], v[1], v[2]};
}

VolumeLayout layout_from(const std::array<int, 3>& shape_zyx, const py::object& voxel_mm, const py::object& origin_mm) {
  for (int n : shape_zyx)
    if (n < 1) throw py::value_error("volume_shape needs three positive sizes (z, y, x)");
  const Eigen::Vector3d voxel = vector3(voxel_mm, "voxel_mm");
  if (!(voxel.array() > 0).all() || !voxel.allFinite())
    throw py::value_error("voxel_mm: expected finite sizes above 0 (mm), got (" + std::to_string(voxel.x()) + ", " +
                          std::to_string(voxel.y()) + ", " + std::to_string(voxel.z()) + ")");
  VolumeLayout l = VolumeLayout::centred({shape_zyx[2], shape_zyx[1], shape_zyx[0]}, voxel);
  if (!origin_mm.is_none()) l.origin_mm = vector3(origin_mm, "origin_mm");
  if (!l.origin_mm.allFinite()) throw py::value_error("origin_mm: expected finite coordinates (mm)");
  return l;
}

py::array_t<float> forward(const ProjectionOperator& A, const FloatArray& volume, const py::object& out) {
  const ConstVolumeSpan x = volume_span(volume, A.domain());
  const StackShape r = A.range();
  py::array_t<float> y = output_array(out, stack_shape(r), "the projections", "(views, rows, cols)");
  const StackSpan span{r.views, r.rows, r.cols, y.mutable_data()};
  interruptible([&] { A.apply(x, span); });
  return y;
}

py::array_t<float> adjoint(const ProjectionOperator& A, const FloatArray& projections, const py::object& out) {
  const StackShape r = A.range();
  require_shape(projections, stack_shape(r), "the projections", "(views, rows, cols)");
  py::array_t<float> x = output_array(out, volume_shape(A.domain()), "the volume", "(z, y, x)");
  const ConstStackSpan y{r.views, r.rows, r.cols, projections.data()};
  interruptible([&] { A.apply_adjoint(y, VolumeSpan{A.domain(), x.mutable_data()}); });
  return x;
}

}  // namespace

void bind_operators(py::module_& m) {
  py::class_<ProjectionOperator, Operator>(m, "Operator", R"doc(
A linear map A from volumes (z, y, x) to projection stacks (views, rows, cols), with its exact
adjoint. Float32 C-contiguous arrays are read and written in place; others are converted once.
)doc")
      .def_property_readonly(
          "volume_shape", [](const ProjectionOperator& A) { return as_tuple(volume_shape(A.domain())); }, "(z, y, x) voxels")
      .def_property_readonly(
          "projection_shape", [](const ProjectionOperator& A) { return as_tuple(stack_shape(A.range())); }, "(views, rows, cols)")
      .def_property_readonly(
          "voxel_mm",
          [](const ProjectionOperator& A) {
            return std::vector<double>(A.domain().voxel_mm.data(), A.domain().voxel_mm.data() + 3);
          },
          "voxel size (x, y, z) in mm")
      .def_property_readonly(
          "origin_mm",
          [](const ProjectionOperator& A) {
            return std::vector<double>(A.domain().origin_mm.data(), A.domain().origin_mm.data() + 3);
          },
          "centre of voxel [0, 0, 0], (x, y, z) in mm, holder frame")
      .def("forward", &forward, py::arg("volume"), py::arg("out") = py::none(),
           "A x: the projections of a (z, y, x) float32 volume, into `out` when given (views, rows, cols).")
      .def("adjoint", &adjoint, py::arg("projections"), py::arg("out") = py::none(),
           "A' y: the back projection of (views, rows, cols) projections, into `out` when given (z, y, x).")
      .def(
          "subset", [](const ProjectionOperator& A, const std::vector<int>& views) { return mutable_operator(A.subset(views)); },
          py::arg("views"), "The operator on these views only (indices, in the order given).");

  py::class_<JosephOperator, ProjectionOperator, std::shared_ptr<JosephOperator>>(m, "Projector", R"doc(
The Joseph projector (matched forward and back projection, SIMD and threads) on per-view 3x4
matrices. Arrays are numpy order: volume (z, y, x), projections (views, rows, cols); points and
sizes in mm are (x, y, z) in the holder frame. The default origin centres the grid on the holder
origin.
)doc")
      .def(py::init([](const DoubleArray& matrices, const std::array<int, 3>& volume_shape, const py::object& voxel_mm,
                       const py::object& origin_mm, const std::array<int, 2>& detector_shape, int threads) {
             ProjectorOptions o;
             o.threads = threads;
             o.validate();
             return std::make_shared<JosephOperator>(matrices_from_numpy(matrices),
                                                     layout_from(volume_shape, voxel_mm, origin_mm), detector_shape[0],
                                                     detector_shape[1], o);
           }),
           py::arg("matrices"), py::arg("volume_shape"), py::arg("voxel_mm") = 1.0, py::arg("origin_mm") = py::none(),
           py::arg("detector_shape"), py::arg("threads") = 0,
           "matrices (views, 3, 4) map holder-frame mm to detector pixels (u = column, v = row); "
           "volume_shape (z, y, x); detector_shape (rows, cols); threads 0 = all.")
      .def_property_readonly("matrices", [](const JosephOperator& A) { return matrices_to_numpy(A.views()); });

  py::class_<BinnedProjection, ProjectionOperator, std::shared_ptr<BinnedProjection>>(
      m, "BinnedProjection",
      "B A: the detector read out in factor x factor blocks (their mean); a partial last row or column is dropped.")
      .def(py::init([](const Operator& inner, int factor) { return std::make_shared<BinnedProjection>(inner, factor); }),
           py::arg("operator"), py::arg("factor"));

  py::class_<WeightedProjection, ProjectionOperator, std::shared_ptr<WeightedProjection>>(
      m, "WeightedProjection",
      "D A: every pixel multiplied by a fixed factor (views, rows, cols): a mask, a gain, square roots of weights.")
      .def(py::init([](const Operator& inner, const FloatArray& factors) {
             return std::make_shared<WeightedProjection>(inner, stack_copy(factors, "the factors"));
           }),
           py::arg("operator"), py::arg("factors"));
}

}  // namespace ctk::python

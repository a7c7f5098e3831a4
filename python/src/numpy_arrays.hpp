#pragma once
// numpy arrays as the C++ side sees them, without copies where the layout allows: a C-contiguous
// float32 array is read (or written) in place; anything else is converted once, by numpy, on the
// way in. Arrays handed to Python either are numpy's own (filled in place) or own a C++ buffer
// through a capsule, so nothing is copied on the way out.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <array>
#include <memory>
#include <string>
#include <utility>

#include "ctk/core/projection_stack.hpp"
#include "ctk/core/volume.hpp"

namespace ctk::python {

namespace py = pybind11;

/// Converts (copies) only what is not already C-contiguous float32.
using FloatArray = py::array_t<float, py::array::c_style | py::array::forcecast>;

inline std::string shape_text(const py::array& a) {
  std::string s = "(";
  for (py::ssize_t d = 0; d < a.ndim(); ++d) s += (d ? ", " : "") + std::to_string(a.shape(d));
  return s + (a.ndim() == 1 ? ",)" : ")");
}

/// Throws ValueError naming `what` unless `a` has exactly `shape`.
template <std::size_t N>
void require_shape(const py::array& a, const std::array<py::ssize_t, N>& shape, const char* what, const char* axes) {
  bool same = a.ndim() == static_cast<py::ssize_t>(N);
  for (std::size_t d = 0; same && d < N; ++d) same = a.shape(static_cast<py::ssize_t>(d)) == shape[d];
  if (!same) {
    std::string expected = "(";
    for (std::size_t d = 0; d < N; ++d) expected += (d ? ", " : "") + std::to_string(shape[d]);
    throw py::value_error(std::string(what) + " has shape " + shape_text(a) + ", expected " + expected + ") " + axes);
  }
}

inline std::array<py::ssize_t, 3> volume_shape(const VolumeLayout& l) { return {l.size[2], l.size[1], l.size[0]}; }

/// The voxels of `a`, shape (z, y, x) as `layout` says, read in place.
inline ConstVolumeSpan volume_span(const FloatArray& a, const VolumeLayout& layout) {
  require_shape(a, volume_shape(layout), "the volume", "(z, y, x)");
  return {layout, a.data()};
}

/// A writable C-contiguous float32 array of this shape (numpy allocates it), or `out` when given,
/// which must be one already (it is filled in place; nothing is converted).
template <std::size_t N>
py::array_t<float> output_array(const py::object& out, const std::array<py::ssize_t, N>& shape, const char* what,
                                const char* axes) {
  if (out.is_none()) return py::array_t<float>(std::vector<py::ssize_t>(shape.begin(), shape.end()));
  auto given = py::array::ensure(out);
  if (!given || !py::isinstance<py::array_t<float>>(given) || !(given.flags() & py::array::c_style) || !given.writeable())
    throw py::value_error(std::string("out= must be a writable C-contiguous float32 array for ") + what);
  require_shape(given, shape, what, axes);
  return py::reinterpret_borrow<py::array_t<float>>(given);
}

/// A C++ object handed to numpy: the array views `data` inside it and keeps it alive.
template <class Owner>
py::array_t<float> owning_array(std::unique_ptr<Owner> owner, float* data, std::vector<py::ssize_t> shape) {
  py::capsule keep(owner.get(), [](void* p) { delete static_cast<Owner*>(p); });
  static_cast<void>(owner.release());  // the capsule owns it now
  return py::array_t<float>(std::move(shape), data, keep);
}

inline py::array_t<float> to_numpy(Volume&& v) {
  auto owner = std::make_unique<Volume>(std::move(v));
  const auto s = volume_shape(owner->layout);
  float* data = owner->data.data();
  return owning_array(std::move(owner), data, {s[0], s[1], s[2]});
}

inline py::array_t<float> to_numpy(ProjectionStack&& s) {
  auto owner = std::make_unique<ProjectionStack>(std::move(s));
  float* data = owner->data.data();
  const std::vector<py::ssize_t> shape{owner->views, owner->rows, owner->cols};
  return owning_array(std::move(owner), data, shape);
}

/// A stack copied from `a` (views, rows, cols): the solvers work on owned stacks.
inline ProjectionStack stack_copy(const FloatArray& a, const char* what) {
  if (a.ndim() != 3) throw py::value_error(std::string(what) + " has shape " + shape_text(a) + ", expected (views, rows, cols)");
  ProjectionStack s(static_cast<int>(a.shape(0)), static_cast<int>(a.shape(1)), static_cast<int>(a.shape(2)));
  std::copy(a.data(), a.data() + a.size(), s.data.begin());
  return s;
}

}  // namespace ctk::python

// The simulator's phantoms as a truth to score a reconstruction against: built-in names or
// ctk-phantom/1 files, voxelised on a grid in the holder frame.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <array>
#include <cmath>
#include <string>
#include <vector>

#include "bindings.hpp"
#include "ctk/phantoms/builtin_phantoms.hpp"
#include "ctk/phantoms/render.hpp"
#include "numpy_arrays.hpp"

namespace ctk::python {

namespace {

// The grid as numpy gives it: shape (z, y, x), voxel_mm and origin_mm (x, y, z), checked.
VolumeLayout grid(const std::array<int, 3>& shape, const std::array<double, 3>& voxel_mm,
                  const std::array<double, 3>& origin_mm) {
  for (int n : shape)
    if (n <= 0) throw py::value_error("shape: expected (z, y, x) voxel counts above 0");
  for (double d : voxel_mm)
    if (!(d > 0) || !std::isfinite(d)) throw py::value_error("voxel_mm: expected finite sizes above 0 (mm)");
  VolumeLayout l;
  l.size = {shape[2], shape[1], shape[0]};
  l.voxel_mm = {voxel_mm[0], voxel_mm[1], voxel_mm[2]};
  l.origin_mm = {origin_mm[0], origin_mm[1], origin_mm[2]};
  return l;
}

}  // namespace

void bind_phantoms(py::module_& m) {
  m.def(
      "voxelise",
      [](const std::vector<std::string>& phantoms, const std::array<int, 3>& shape, const std::array<double, 3>& voxel_mm,
         const std::array<double, 3>& origin_mm) {
        const VolumeLayout l = grid(shape, voxel_mm, origin_mm);
        const Phantom phantom = sample_of(phantoms);
        Volume v = [&] {
          py::gil_scoped_release unlocked;
          return voxelised(phantom, l);
        }();
        return to_numpy(std::move(v));
      },
      py::arg("phantoms"), py::arg("shape"), py::arg("voxel_mm"), py::arg("origin_mm"),
      "The phantoms (built-in names or ctk-phantom/1 files, as `ctk simulate --phantom` takes them) voxelised, "
      "each voxel the mean attenuation (1/mm) at 2 x 2 x 2 points inside it: an array (z, y, x) of `shape`, "
      "voxel_mm and origin_mm (the centre of voxel 0) as read_volume gives them, in the holder frame.");
  m.def(
      "voxelise_per_material",
      [](const std::vector<std::string>& phantoms, const std::array<int, 3>& shape, const std::array<double, 3>& voxel_mm,
         const std::array<double, 3>& origin_mm) {
        const VolumeLayout l = grid(shape, voxel_mm, origin_mm);
        const Phantom phantom = sample_of(phantoms);
        std::vector<MaterialVolume> parts = [&] {
          py::gil_scoped_release unlocked;
          return voxelised_per_material(phantom, l);
        }();
        py::dict out;
        for (MaterialVolume& p : parts) out[py::str(p.material)] = to_numpy(std::move(p.volume));
        return out;
      },
      py::arg("phantoms"), py::arg("shape"), py::arg("voxel_mm"), py::arg("origin_mm"),
      "As voxelise, split by the primitives' material: a dict from material name ('' for primitives without one) "
      "to its primitives alone voxelised (holes count with the material they are cut from); the arrays add up to "
      "voxelise's. Scoring a reconstruction with each material at its own level (beam hardening moves each "
      "material's level differently) needs them.");
}

}  // namespace ctk::python

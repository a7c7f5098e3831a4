#pragma once
// The parts of the extension module, one file each.
#include <pybind11/pybind11.h>

namespace ctk::python {

void bind_files(pybind11::module_& m);         // scan, geometry and cone_vec files; matrices
void bind_operators(pybind11::module_& m);     // the projector and its variants as operators
void bind_solvers(pybind11::module_& m);       // WLS-CG, SIRT, FDK
void bind_measurements(pybind11::module_& m);  // a scan's line integrals, weights, matrices; images
void bind_workflows(pybind11::module_& m);     // import of a circular scan, the markerless loop
void bind_benchmarks(pybind11::module_& m);    // the standard problem; C++-side timing
void bind_planning(pybind11::module_& m);      // view planning, simulated and in a lab
void bind_phantoms(pybind11::module_& m);      // the simulator's phantoms voxelised (a truth)

}  // namespace ctk::python

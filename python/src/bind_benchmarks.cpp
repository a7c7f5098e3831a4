// What benchmarks/python_overhead.py needs to time the binding against C++ in the same process:
// the standard problem, and the operator's forward projection timed from C++ on the same arrays;
// and `ctk bench` itself (the projector against the reference in the same run).
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <chrono>
#include <optional>
#include <string>
#include <vector>

#include "bindings.hpp"
#include "conversions.hpp"
#include "ctk/proj/projection_operator.hpp"
#include "ctk/proj/projector_benchmark.hpp"
#include "ctk/proj/standard_problem.hpp"
#include "interruptible.hpp"
#include "numpy_arrays.hpp"
#include "python_bridge.hpp"

namespace ctk::python {

void bind_benchmarks(py::module_& m) {
  m.def(
      "_standard_problem",
      [](const std::string& trajectory, int views, int scale) {
        if (trajectory != "circular" && trajectory != "spherical")
          throw py::value_error("trajectory must be 'circular' or 'spherical'");
        const StandardProblem p = standard_problem(
            trajectory == "circular" ? StandardTrajectory::circular : StandardTrajectory::spherical, views, scale);
        py::dict d;
        d["matrices"] = matrices_to_numpy(p.views);
        d["volume_shape"] = py::make_tuple(p.layout.size[2], p.layout.size[1], p.layout.size[0]);
        d["voxel_mm"] = std::vector<double>{p.layout.voxel_mm.x(), p.layout.voxel_mm.y(), p.layout.voxel_mm.z()};
        d["origin_mm"] = std::vector<double>{p.layout.origin_mm.x(), p.layout.origin_mm.y(), p.layout.origin_mm.z()};
        d["detector_shape"] = py::make_tuple(p.rows, p.cols);
        return d;
      },
      py::arg("trajectory"), py::arg("views") = 360, py::arg("scale") = 1);
  m.def(
      "_time_forward_in_cpp",
      [](const ProjectionOperator& A, const FloatArray& volume, py::array_t<float> out) {
        const ConstVolumeSpan x = volume_span(volume, A.domain());
        const StackShape r = A.range();
        require_shape(out, std::array<py::ssize_t, 3>{r.views, r.rows, r.cols}, "out", "(views, rows, cols)");
        const StackSpan y{r.views, r.rows, r.cols, out.mutable_data()};
        py::gil_scoped_release free;
        const auto start = std::chrono::steady_clock::now();
        A.apply(x, y);
        return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
      },
      py::arg("operator"), py::arg("volume"), py::arg("out"), "Seconds of one forward projection timed inside C++.");
  m.def(
      "_bench",
      [](int views, int reference_views, int scale, int threads, int repeat, const std::string& simd, const py::object& log) {
        ProjectorBenchmarkOptions o;
        o.views = views;
        o.reference_views = reference_views;
        o.scale = scale;
        o.threads = threads;
        o.repeat = repeat;
        o.simd = simd;
        o.validate();
        PythonBridge bridge;
        std::optional<ProjectorBenchmark> b;
        interruptible([&] { b = run_projector_benchmark(o, bridge.log(log)); });
        bridge.raise_if_stopped();
        py::dict d;
        d["report"] = to_python(b->report);
        d["brief"] = b->brief();
        return d;
      },
      py::arg("views"), py::arg("reference_views"), py::arg("scale"), py::arg("threads"), py::arg("repeat"), py::arg("simd"),
      py::arg("log"));
}

}  // namespace ctk::python

// The solvers on any operator: each iteration reported to a Python callable that may stop the
// solve; Ctrl-C (KeyboardInterrupt) stops it within the iteration under way (interruptible.hpp),
// the GIL released while it computes.
#include <pybind11/functional.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <memory>
#include <optional>
#include <string>

#include "bindings.hpp"
#include "conversions.hpp"
#include "ctk/proj/joseph_operator.hpp"
#include "ctk/recon/fdk.hpp"
#include "ctk/recon/ordered_subsets.hpp"
#include "ctk/recon/os_sqs.hpp"
#include "ctk/recon/sirt.hpp"
#include "ctk/recon/solver_state.hpp"
#include "ctk/recon/wls_cg.hpp"
#include "interruptible.hpp"
#include "numpy_arrays.hpp"
#include "python_bridge.hpp"

namespace ctk::python {

namespace {

py::dict log_dict(const IterationLog& l) {
  py::dict d;
  d["iteration"] = l.iteration;
  d["cost"] = l.cost;
  d["data_term"] = l.data_term;
  d["regulariser_term"] = l.regulariser_term;
  d["relative_gradient"] = l.relative_gradient;
  d["seconds"] = l.seconds;
  return d;
}

// A solver running without the GIL, seen from Python: the callback sees each iteration and returns
// False to stop; an exception in it, or Ctrl-C, stops the solver and is raised once it returns.
class SolverControl {
 public:
  explicit SolverControl(py::object callback) : callback_(std::move(callback)) {
    checkpointing_.save = [](const SolverSnapshot&) {};
    checkpointing_.stop_requested = [this] { return bridge_.stop_requested(); };
  }
  IterationCallback on_iteration() {
    return [this](const IterationLog& l) {
      if (callback_.is_none()) return;
      bridge_.with_gil([&] {
        const py::object answer = callback_(log_dict(l));
        if (!answer.is_none() && !answer.cast<bool>()) bridge_.request_stop();
      });
    };
  }
  const Checkpointing* checkpointing() const { return &checkpointing_; }
  /// Raises what the callback or Ctrl-C raised; otherwise the report as a dict.
  py::object finish(const SolverReport& report) {
    bridge_.raise_if_stopped();
    py::object r = to_python(to_json(report));
    if (bridge_.stopped_by_request()) r["stop_reason"] = "stopped by the callback";
    return r;
  }

 private:
  py::object callback_;
  PythonBridge bridge_;
  Checkpointing checkpointing_;
};

Volume start_volume(const ProjectionOperator& A, const py::object& x0) {
  Volume x(A.domain());
  if (!x0.is_none()) {
    const FloatArray given = x0.cast<FloatArray>();
    const ConstVolumeSpan s = volume_span(given, A.domain());
    std::copy(s.data, s.data + x.data.size(), x.data.begin());
  }
  return x;
}

ProjectionStack data_stack(const ProjectionOperator& A, const FloatArray& b, const char* what) {
  const StackShape r = A.range();
  require_shape(b, std::array<py::ssize_t, 3>{r.views, r.rows, r.cols}, what, "(views, rows, cols)");
  return stack_copy(b, what);
}

py::tuple wls_cg(const ProjectionOperator& A, const FloatArray& b, const py::object& weights, const py::object& x0,
                 int iterations, double tolerance, double lam, const std::string& regulariser, const std::string& preconditioner,
                 const py::object& callback) {
  WlsOptions o;
  o.iterations = iterations;
  o.tolerance = tolerance;
  o.lambda = lam;
  o.regulariser = regulariser_from_string(regulariser);  // std::invalid_argument: ValueError
  o.preconditioner = cg_preconditioner_from_string(preconditioner);
  o.validate();
  const ProjectionStack data = data_stack(A, b, "b");
  std::optional<ProjectionStack> w;
  if (!weights.is_none()) w = data_stack(A, weights.cast<FloatArray>(), "weights");
  Volume x = start_volume(A, x0);
  SolverControl control(callback);
  SolverReport report;
  interruptible(
      [&] { report = solve_wls_cg(A, data, w ? &*w : nullptr, x, o, control.on_iteration(), control.checkpointing()); });
  py::object r = control.finish(report);
  return py::make_tuple(to_numpy(std::move(x)), r);
}

py::tuple sirt(const ProjectionOperator& A, const FloatArray& b, const py::object& x0, int iterations, double relaxation,
               bool non_negative, const py::object& callback) {
  const SirtOptions o{iterations, relaxation, non_negative};
  o.validate();
  const ProjectionStack data = data_stack(A, b, "b");
  Volume x = start_volume(A, x0);
  SolverControl control(callback);
  SolverReport report;
  interruptible([&] { report = solve_sirt(A, data, x, o, control.on_iteration(), control.checkpointing()); });
  py::object r = control.finish(report);
  return py::make_tuple(to_numpy(std::move(x)), r);
}

py::tuple os_sqs(const ProjectionOperator& A, const FloatArray& b, const py::object& weights, const py::object& x0, int epochs,
                 int subsets, double lam, const std::string& regulariser, double huber_delta, bool non_negative,
                 const py::object& callback) {
  OsSqsOptions o;
  o.epochs = epochs;
  o.lambda = lam;
  o.regulariser = regulariser_from_string(regulariser);  // std::invalid_argument: ValueError
  o.huber_delta = huber_delta;
  o.non_negative = non_negative;
  o.validate();
  if (subsets < 1) throw py::value_error("subsets must be at least 1");
  const ProjectionStack data = data_stack(A, b, "b");
  std::optional<ProjectionStack> w;
  if (!weights.is_none()) w = data_stack(A, weights.cast<FloatArray>(), "weights");
  // Subsets spread over the views' source directions where the operator knows its matrices (the
  // projector); otherwise interleaved by index.
  std::vector<std::vector<int>> groups;
  if (const auto* joseph = dynamic_cast<const JosephOperator*>(&A)) {
    groups = ordered_subsets(joseph->views(), subsets);
  } else {
    groups.resize(static_cast<std::size_t>(std::min(subsets, A.range().views)));
    for (int v = 0; v < A.range().views; ++v) groups[static_cast<std::size_t>(v) % groups.size()].push_back(v);
  }
  Volume x = start_volume(A, x0);
  SolverControl control(callback);
  SolverReport report;
  interruptible([&] {
    report =
        solve_os_sqs(A, data, w ? &*w : nullptr, x, groups, o, control.on_iteration(), control.checkpointing()->stop_requested);
  });
  py::object r = control.finish(report);
  return py::make_tuple(to_numpy(std::move(x)), r);
}

py::array_t<float> fdk(const JosephOperator& A, const FloatArray& projections, const std::string& window) {
  if (window != "hann" && window != "ram-lak") throw py::value_error("window must be 'hann' or 'ram-lak', not '" + window + "'");
  ProjectionStack filtered = data_stack(A, projections, "the projections");  // filtered in place: a copy
  Volume x(A.domain());
  interruptible([&] {
    // FDK's filter scale is the pixel pitch times the focal length in pixels: any pitch gives the same.
    fdk_reconstruct(A.views(), filtered, {filtered.cols, filtered.rows, 1.0, 1.0}, x,
                    window == "hann" ? RampWindow::hann : RampWindow::ram_lak);
  });
  return to_numpy(std::move(x));
}

}  // namespace

void bind_solvers(py::module_& m) {
  m.def("_wls_cg", &wls_cg, py::arg("operator"), py::arg("b"), py::arg("weights"), py::arg("x0"), py::arg("iterations"),
        py::arg("tolerance"), py::arg("lam"), py::arg("regulariser"), py::arg("preconditioner"), py::arg("callback"));
  m.def("_sirt", &sirt, py::arg("operator"), py::arg("b"), py::arg("x0"), py::arg("iterations"), py::arg("relaxation"),
        py::arg("non_negative"), py::arg("callback"));
  m.def("_os_sqs", &os_sqs, py::arg("operator"), py::arg("b"), py::arg("weights"), py::arg("x0"), py::arg("epochs"),
        py::arg("subsets"), py::arg("lam"), py::arg("regulariser"), py::arg("huber_delta"), py::arg("non_negative"),
        py::arg("callback"));
  m.def("fdk", &fdk, py::arg("projector"), py::arg("projections"), py::arg("window") = "hann", R"doc(
FDK for a circular scan on the projector's matrices, volume and detector: the sources must lie on
a circle (ValueError with the deviation otherwise); short scans get Parker weights. `projections`
are line integrals (views, rows, cols), copied (the filter works in place). Returns (z, y, x).
)doc");
}

}  // namespace ctk::python

// The planning workflows from Python: against the simulated lab (with the trajectory comparison)
// and with a lab through request/answer files, on libplan's entry points as `ctk plan` calls them.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include <filesystem>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "bindings.hpp"
#include "conversions.hpp"
#include "ctk/plan/planned_scan.hpp"
#include "ctk/plan/simulated_planning_run.hpp"
#include "interruptible.hpp"
#include "python_bridge.hpp"

namespace ctk::python {

namespace {

namespace fs = std::filesystem;

// The keywords of a request, each read into its field once; a keyword no field takes, or a value
// of the wrong type, is a ValueError naming it.
class Keywords {
 public:
  explicit Keywords(const py::dict& given) : given_(from_python(given)) {}
  template <class T>
  void take(const char* key, T& field) {
    taken_.insert(key);
    const auto it = given_.find(key);
    if (it == given_.end() || it->is_null()) return;
    try {
      field = it->get<T>();
    } catch (const nlohmann::json::exception&) {
      throw py::value_error(std::string(key) + ": " + it->dump() + " is not of the type expected");
    }
  }
  void finish() const {
    for (const auto& [key, value] : given_.items())
      if (!taken_.count(key)) throw py::value_error("unknown keyword '" + key + "'");
  }

 private:
  nlohmann::json given_;
  std::set<std::string> taken_;
};

void take_plan(Keywords& k, PlanRequest& p) {
  k.take("views", p.views);
  k.take("scout_nside", p.scout_nside);
  k.take("candidate_nside", p.candidate_nside);
  k.take("damage_exponent", p.damage_exponent);
  k.take("spread_exponent", p.spread_exponent);
  k.take("widest_gap_fraction", p.widest_gap_fraction);
  k.take("edge_tangency_weight", p.edge_tangency_weight);
  k.take("tangent_width_deg", p.tangent_width_deg);
  k.take("seed", p.seed);
  k.take("coarse_size", p.coarse_size);
  k.take("coarse_voxel_mm", p.coarse_voxel_mm);
  k.take("binning", p.binning);
}

void take_simulated(Keywords& k, SimulatedPlanRequest& r) {
  take_plan(k, r.plan);
  k.take("phantoms", r.phantoms);
  std::string out = r.out.string();
  k.take("out", out);
  r.out = out;
  std::array<int, 2> shape{r.rows, r.cols};
  k.take("detector_shape", shape);
  r.rows = shape[0];
  r.cols = shape[1];
  k.take("pitch_mm", r.pitch_mm);
  k.take("sdd_mm", r.sdd_mm);
  k.take("sod_mm", r.sod_mm);
  k.take("kvp", r.kvp);
  k.take("filter_al_mm", r.filter_al_mm);
  k.take("flat_counts", r.flat_counts);
  k.take("compare", r.compare);
  k.take("compare_only", r.compare_only);
  k.take("random_draws", r.random_draws);
  k.take("eval_size", r.comparison.size);
  k.take("eval_voxel_mm", r.comparison.voxel_mm);
  k.take("eval_iterations", r.comparison.iterations);
  k.take("eval_lambda", r.comparison.lambda);
  k.take("eval_binning", r.comparison.binning);
}

py::dict trajectory_to_python(const PlanningRun& r) {
  py::dict d;
  d["name"] = r.name;
  d["folder"] = r.folder;
  d["brief"] = r.brief();
  d["report"] = to_python(r.report());
  std::vector<ProjectionMatrix> calibrated;
  for (const PlannedViewRecord& v : r.result.views)
    if (v.calibrated) calibrated.push_back(*v.P);
  d["matrices"] = matrices_to_numpy(calibrated);
  py::list pictures;
  for (const fs::path& p : r.pictures) pictures.append(p);
  d["pictures"] = pictures;
  d["seconds"] = r.seconds;
  return d;
}

// A request's record to `callback(trajectory, record)` with the GIL; False from it, an exception
// or Ctrl-C ends the run by an exception the bridge turns back into what Python raised.
struct Stopped {};

std::function<void(const std::string&, const PlannedViewRecord&)> view_hook(PythonBridge& bridge, const py::object& callback) {
  return [&bridge, callback](const std::string& trajectory, const PlannedViewRecord& v) {
    bridge.with_gil([&] {
      if (!callback.is_none() && callback(trajectory, to_python(planned_view_to_json(v))).is(py::bool_(false)))
        bridge.request_stop();
    });
    if (bridge.stop_requested()) throw Stopped{};
  };
}

py::dict plan_simulated(const py::dict& keywords, const py::object& callback, const py::object& log) {
  SimulatedPlanRequest r;
  Keywords k(keywords);
  take_simulated(k, r);
  k.finish();
  r.validate();
  PythonBridge bridge;
  const auto on_view = view_hook(bridge, callback);
  SimulatedPlanningHooks hooks;
  hooks.view = [&](const std::string& trajectory, int, const PlannedViewRecord& v) { on_view(trajectory, v); };
  hooks.log = bridge.log(log);
  std::optional<SimulatedPlanningRun> run;
  try {
    interruptible([&] { run = run_simulated_planning(r, hooks); });
  } catch (const Stopped&) {
  }
  bridge.raise_if_stopped();
  py::dict d;
  d["stopped"] = !run.has_value();
  if (!run) return d;
  py::list trajectories;
  for (const PlanningRun& t : run->trajectories) trajectories.append(trajectory_to_python(t));
  d["trajectories"] = trajectories;
  d["comparison"] = run->comparison ? to_python(run->comparison->report) : py::none();
  d["brief"] = run->brief();
  d["seconds"] = run->seconds;
  return d;
}

py::dict plan_lab(const py::dict& keywords, const py::object& callback) {
  LabPlanRequest r;
  Keywords k(keywords);
  take_plan(k, r.plan);
  std::string lab, setup, out;
  k.take("lab", lab);
  k.take("setup", setup);
  k.take("out", out);
  r.lab = lab;
  r.setup = setup;
  r.out = out;
  k.take("sod_mm", r.sod_mm);
  k.take("timeout_s", r.timeout_s);
  k.finish();
  r.validate();
  PythonBridge bridge;
  const auto on_view = view_hook(bridge, callback);
  std::optional<PlanningRun> run;
  try {
    interruptible([&] { run = run_lab_planning(r, [&](const PlannedViewRecord& v) { on_view("planned", v); }); });
  } catch (const Stopped&) {
  }
  bridge.raise_if_stopped();
  py::dict d;
  d["stopped"] = !run.has_value();
  if (run) d["trajectory"] = trajectory_to_python(*run);
  return d;
}

// The defaults of every keyword, as the library has them (the Python signatures are checked
// against these by the tests).
py::dict plan_defaults() {
  const SimulatedPlanRequest s;
  const LabPlanRequest l;
  const PlanRequest& p = s.plan;
  py::dict d;
  d["views"] = p.views;
  d["scout_nside"] = p.scout_nside;
  d["candidate_nside"] = p.candidate_nside;
  d["damage_exponent"] = p.damage_exponent;
  d["spread_exponent"] = p.spread_exponent;
  d["widest_gap_fraction"] = p.widest_gap_fraction;
  d["edge_tangency_weight"] = p.edge_tangency_weight;
  d["tangent_width_deg"] = p.tangent_width_deg;
  d["seed"] = p.seed;
  d["coarse_size"] = p.coarse_size;
  d["coarse_voxel_mm"] = p.coarse_voxel_mm;
  d["binning"] = p.binning;
  d["detector_shape"] = py::make_tuple(s.rows, s.cols);
  d["pitch_mm"] = s.pitch_mm;
  d["sdd_mm"] = s.sdd_mm;
  d["sod_mm"] = s.sod_mm;
  d["kvp"] = s.kvp;
  d["filter_al_mm"] = s.filter_al_mm;
  d["flat_counts"] = s.flat_counts;
  d["compare"] = s.compare;
  d["compare_only"] = s.compare_only;
  d["random_draws"] = s.random_draws;
  d["eval_size"] = s.comparison.size;
  d["eval_voxel_mm"] = s.comparison.voxel_mm;
  d["eval_iterations"] = s.comparison.iterations;
  d["eval_lambda"] = s.comparison.lambda;
  d["eval_binning"] = s.comparison.binning;
  d["timeout_s"] = l.timeout_s;
  return d;
}

}  // namespace

void bind_planning(py::module_& m) {
  m.def("_plan", &plan_simulated, py::arg("keywords"), py::arg("callback"), py::arg("log"));
  m.def("_plan_lab", &plan_lab, py::arg("keywords"), py::arg("callback"));
  m.def("_plan_defaults", &plan_defaults);
}

}  // namespace ctk::python

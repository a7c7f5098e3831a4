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
#include "ctk/geom/trajectory.hpp"
#include "ctk/plan/direction_damage.hpp"
#include "ctk/plan/direction_list.hpp"
#include "ctk/plan/plan_trajectory.hpp"
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

// Each request's keywords with the field each names, once: `f(key, field)` for every one (the
// request const or not). The paths and the detector's shape are converted apart.
template <class Plan, class F>
void plan_keywords(Plan& p, F&& f) {
  f("views", p.views);
  f("scout_nside", p.scout_nside);
  f("candidate_nside", p.candidate_nside);
  f("damage_exponent", p.damage_exponent);
  f("spread_exponent", p.spread_exponent);
  f("widest_gap_fraction", p.widest_gap_fraction);
  f("edge_tangency_weight", p.edge_tangency_weight);
  f("tangent_width_deg", p.tangent_width_deg);
  f("picture_median", p.picture_median);
  f("seed", p.seed);
  f("coarse_size", p.coarse_size);
  f("coarse_voxel_mm", p.coarse_voxel_mm);
  f("binning", p.binning);
}

template <class Simulated, class F>
void simulated_keywords(Simulated& r, F&& f) {
  plan_keywords(r.plan, f);
  f("pitch_mm", r.pitch_mm);
  f("sdd_mm", r.sdd_mm);
  f("sod_mm", r.sod_mm);
  f("kvp", r.kvp);
  f("filter_al_mm", r.filter_al_mm);
  f("flat_counts", r.flat_counts);
  f("compare", r.compare);
  f("compare_only", r.compare_only);
  f("random_draws", r.random_draws);
  f("eval_size", r.comparison.size);
  f("eval_voxel_mm", r.comparison.voxel_mm);
  f("eval_iterations", r.comparison.iterations);
  f("eval_lambda", r.comparison.lambda);
  f("eval_binning", r.comparison.binning);
}

template <class Lab, class F>
void lab_keywords(Lab& r, F&& f) {
  plan_keywords(r.plan, f);
  f("sod_mm", r.sod_mm);
  f("timeout_s", r.timeout_s);
}

void take_path(Keywords& k, const char* key, fs::path& path) {
  std::string given = path.string();
  k.take(key, given);
  path = given;
}

void take_simulated(Keywords& k, SimulatedPlanRequest& r) {
  simulated_keywords(r, [&](const char* key, auto& field) { k.take(key, field); });
  k.take("phantoms", r.phantoms);
  k.take("holder", r.holder);
  take_path(k, "out", r.out);
  std::vector<std::string> lists;
  k.take("compare_directions", lists);
  r.compare_directions.assign(lists.begin(), lists.end());
  std::array<int, 2> shape{r.rows, r.cols};
  k.take("detector_shape", shape);
  r.rows = shape[0];
  r.cols = shape[1];
}

void take_lab(Keywords& k, LabPlanRequest& r) {
  lab_keywords(r, [&](const char* key, auto& field) { k.take(key, field); });
  take_path(k, "lab", r.lab);
  take_path(k, "setup", r.setup);
  take_path(k, "out", r.out);
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
// or Ctrl-C ends the run (the bridge then raises what Python raised).
std::function<void(const std::string&, const PlannedViewRecord&)> view_hook(PythonBridge& bridge, const py::object& callback) {
  return [&bridge, callback](const std::string& trajectory, const PlannedViewRecord& v) {
    bridge.with_gil([&] {
      if (!callback.is_none() && callback(trajectory, to_python(planned_view_to_json(v))).is(py::bool_(false)))
        bridge.request_stop();
    });
    bridge.end_run_if_stopping();
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
  bridge.run_stoppable([&] { run = run_simulated_planning(r, hooks); });
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
  take_lab(k, r);
  k.finish();
  r.validate();
  PythonBridge bridge;
  const auto on_view = view_hook(bridge, callback);
  std::optional<PlanningRun> run;
  bridge.run_stoppable([&] { run = run_lab_planning(r, [&](const PlannedViewRecord& v) { on_view("planned", v); }); });
  py::dict d;
  d["stopped"] = !run.has_value();
  if (run) d["trajectory"] = trajectory_to_python(*run);
  return d;
}

// The defaults of every keyword, as the library has them (the Python signatures are checked
// against these by the tests).
py::dict plan_defaults() {
  py::dict d;
  const auto put = [&](const char* key, const auto& value) { d[key] = value; };
  const SimulatedPlanRequest s;
  simulated_keywords(s, put);
  d["detector_shape"] = py::make_tuple(s.rows, s.cols);
  d["compare_directions"] = py::tuple();
  const LabPlanRequest l;
  lab_keywords(l, put);
  return d;
}

py::array_t<double> directions_to_numpy(const std::vector<Eigen::Vector3d>& directions) {
  py::array_t<double> a({static_cast<py::ssize_t>(directions.size()), py::ssize_t{3}});
  auto r = a.mutable_unchecked<2>();
  for (std::size_t i = 0; i < directions.size(); ++i)
    for (int k = 0; k < 3; ++k) r(static_cast<py::ssize_t>(i), k) = directions[i][k];
  return a;
}

std::vector<Eigen::Vector3d> directions_from_numpy(const py::array_t<double, py::array::c_style | py::array::forcecast>& a) {
  if (a.ndim() != 2 || a.shape(1) != 3) throw py::value_error("directions: expected an array of shape (n, 3)");
  const auto r = a.unchecked<2>();
  std::vector<Eigen::Vector3d> d;
  for (py::ssize_t i = 0; i < a.shape(0); ++i) d.emplace_back(r(i, 0), r(i, 1), r(i, 2));
  return d;
}

// The planner's directions: its candidates (HEALPix cell centres) or the whole sphere's order.
py::array_t<double> planning_directions(int nside, const std::string& order) {
  if (nside < 1) throw py::value_error("nside: expected at least 1, got " + std::to_string(nside));
  if (order == "healpix") return directions_to_numpy(HealpixSphere(nside).directions());
  if (order == "whole-sphere") return directions_to_numpy(whole_sphere_order(nside));
  throw py::value_error("order: expected 'healpix' or 'whole-sphere', got '" + order + "'");
}

// The matrix of a view along `direction` with the detector centred on the beam, as the planner
// pictures it (a robot's view along the same direction differs by its roll and its errors).
py::array_t<double> view_matrix(const std::array<double, 3>& beam, const std::array<int, 2>& detector_shape, double pitch_mm,
                                double sdd_mm, double sod_mm) {
  const Eigen::Vector3d direction(beam[0], beam[1], beam[2]);
  if (direction.norm() < 1e-9) throw py::value_error("direction: expected a vector of non-zero length");
  const Detector detector{detector_shape[1], detector_shape[0], pitch_mm, pitch_mm};
  return matrices_to_numpy({virtual_view(direction, Intrinsics::from_setup(sdd_mm, detector, detector.centre_px()), sod_mm)});
}

// The rule's draws with a fixed picture of the sample (the truth, for a check of the rule apart
// from the scout's reconstruction), on the planner's coarse grid as the keywords set it.
py::array_t<double> plan_on_picture(const py::dict& keywords, const FloatArray& picture, const py::object& reachable) {
  PlanRequest request;
  DamageGeometry geometry;
  Keywords k(keywords);
  plan_keywords(request, [&](const char* key, auto& field) { k.take(key, field); });
  k.take("sod_mm", geometry.source_to_isocentre_mm);
  k.take("sdd_mm", geometry.source_to_detector_mm);
  k.finish();
  request.validate();  // std::invalid_argument, a ValueError in Python
  const PlanningOptions options = request.planning_options();
  Volume volume(options.coarse_volume);
  const ConstVolumeSpan given = volume_span(picture, volume.layout);
  std::copy(given.data, given.data + volume.data.size(), volume.data.begin());
  std::function<bool(const Eigen::Vector3d&)> allowed;
  if (!reachable.is_none())
    allowed = [&reachable](const Eigen::Vector3d& d) { return reachable(py::make_tuple(d.x(), d.y(), d.z())).cast<bool>(); };
  return directions_to_numpy(ctk::plan_on_picture(volume, options, geometry, allowed));
}

py::dict read_directions(const fs::path& file) {
  const DirectionList list = read_direction_list(file);
  py::dict d;
  d["name"] = list.name;
  d["directions"] = directions_to_numpy(list.directions);
  return d;
}

void write_directions(const fs::path& file, const std::string& name,
                      const py::array_t<double, py::array::c_style | py::array::forcecast>& directions) {
  write_direction_list(file, {name, directions_from_numpy(directions)});
}

}  // namespace

void bind_planning(py::module_& m) {
  m.def("_planning_directions", &planning_directions, py::arg("nside"), py::arg("order"));
  m.def("_view_matrix", &view_matrix, py::arg("direction"), py::arg("detector_shape"), py::arg("pitch_mm"), py::arg("sdd_mm"),
        py::arg("sod_mm"));
  m.def("_read_directions", &read_directions, py::arg("file"));
  m.def("_write_directions", &write_directions, py::arg("file"), py::arg("name"), py::arg("directions"));
  m.def("_plan", &plan_simulated, py::arg("keywords"), py::arg("callback"), py::arg("log"));
  m.def("_plan_lab", &plan_lab, py::arg("keywords"), py::arg("callback"));
  m.def("_plan_defaults", &plan_defaults);
  m.def("_plan_on_picture", &plan_on_picture, py::arg("keywords"), py::arg("picture"), py::arg("reachable"));
}

}  // namespace ctk::python

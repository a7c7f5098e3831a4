#include "ctk/plan/planning_run.hpp"

#include <algorithm>
#include <chrono>
#include <sstream>

#include "ctk/core/error.hpp"
#include "ctk/core/volume_file.hpp"
#include "ctk/geom/run_files.hpp"
#include "ctk/measure/projection_reading.hpp"
#include "ctk/plan/plan_pictures.hpp"
#include "ctk/plan/planned_scan.hpp"

namespace ctk {

namespace fs = std::filesystem;

void PlanRequest::validate() const {
  require_option(views >= 2, "PlanRequest.views", "at least 2", views);
  require_option(coarse_size >= 8, "PlanRequest.coarse_size", "at least 8 voxels per axis", coarse_size);
  require_option(coarse_voxel_mm > 0, "PlanRequest.coarse_voxel_mm", "a size above 0", coarse_voxel_mm);
  planning_options();  // the rest as the loop's own options check them
}

PlanningOptions PlanRequest::planning_options() const {
  PlanningOptions p;
  p.scout_nside = scout_nside;
  p.views = views;
  p.coarse_volume = VolumeLayout::centred({coarse_size, coarse_size, coarse_size}, Eigen::Vector3d::Constant(coarse_voxel_mm));
  p.planner.candidate_nside = candidate_nside;
  p.planner.planned_views = views;
  p.planner.damage_exponent = damage_exponent;
  p.planner.spread_exponent = spread_exponent;
  p.planner.widest_gap_fraction = widest_gap_fraction;
  p.planner.edge_tangency_weight = edge_tangency_weight;
  p.edge_tangency.tangent_width_deg = tangent_width_deg;
  p.picture_median = picture_median;
  p.planner.damage_floor_mm = 2 * coarse_voxel_mm;
  p.planner.seed = seed;
  p.reconstruction.binning = binning;
  p.validate();
  return p;
}

std::string PlanningRun::brief() const {
  std::ostringstream s;
  s << folder.string() << ": " << result.calibrated() << " views calibrated, " << result.acquired() << " acquired in "
    << result.views.size() << " requests";
  if (!result.step_seconds.empty())
    s << "; planner step " << result.mean_step_seconds() << " s mean, " << result.max_step_seconds() << " s max";
  s << "; absorbers: "
    << (result.segmentation.voxels > 0 ? std::to_string(result.segmentation.voxels) + " coarse voxels"
                                       : result.segmentation.note);
  return s.str();
}

nlohmann::json PlanningRun::report() const { return trajectory_to_json(result); }

PlanningRun write_planning_run(std::string name, const fs::path& folder, PlanningResult result, const PlanningSetup& setup,
                               bool map, double seconds) {
  PlanningRun run{std::move(name), folder, std::move(result), {}, seconds};
  write_planned_scan(run.result, setup, folder);
  if (map) {
    write_plan_map_png(run.result, folder / "plan-map.png");
    write_volume(run.result.coarse, folder / "coarse.nrrd");
    run.pictures.push_back(folder / "plan-map.png");
  }
  return run;
}

void LabPlanRequest::validate() const {
  plan.validate();
  require_choice(!lab.empty(), "LabPlanRequest.lab", "the folder shared with the acquisition process", "nothing");
  require_choice(!setup.empty(), "LabPlanRequest.setup", "the lab's ctk-scan/1 file", "nothing");
  require_choice(!out.empty(), "LabPlanRequest.out", "a folder for the planned scan", "nothing");
  require_option(sod_mm > 0, "LabPlanRequest.sod_mm", "a distance above 0", sod_mm);
  require_option(timeout_s >= 1, "LabPlanRequest.timeout_s", "at least 1 second", timeout_s);
}

PlanningSetup lab_planning_setup(const fs::path& file, const ScanDescription& scan, double sod_mm) {
  if (!scan.panda) throw InputError(file.string(), "pose_source", "lab mode needs a panda pose source (the robot's frames)");
  if (!scan.holder) throw InputError(file.string(), "holder", "lab mode calibrates every view: the holder is required");
  const std::optional<FlatDark> fd = read_flat_dark(scan);
  if (!fd) throw InputError(file.string(), "projections.flat", "lab mode needs counts with flat and dark frames");
  PlanningSetup s;
  s.setup.detector = scan.detector;
  s.setup.principal_point_px = scan.principal_point_px;
  s.setup.source_to_detector_mm = scan.source_to_detector_mm;
  s.setup.source_to_isocentre_mm = sod_mm;
  s.setup.T_camera_base = scan.panda->T_camera_base;
  s.setup.T_flange_holder = scan.panda->T_flange_holder;
  s.holder = *scan.holder;
  s.flat = fd->flat;
  s.dark = fd->dark;
  return s;
}

PlanningRun run_lab_planning(const LabPlanRequest& request, const std::function<void(const PlannedViewRecord&)>& on_view) {
  const auto start = std::chrono::steady_clock::now();
  request.validate();
  const PlanningOptions options = request.plan.planning_options();
  const ScanDescription lab_scan = read_scan(request.setup);
  RunFiles files;
  files.scan("setup", request.setup, lab_scan);
  files.input_folder("lab", request.lab);
  for (const char* name : {"scan.json", "joints.csv", "flat.tif", "dark.tif", "geometry.json", "trajectory.json", "plan-map.png",
                           "coarse.nrrd", "plan.html"})
    files.output(std::string("out: ") + name, request.out / name);
  files.check();
  const PlanningSetup setup = lab_planning_setup(request.setup, lab_scan, request.sod_mm);
  FileExchangeAcquisition acquisition(request.lab, setup.setup.detector.cols, setup.setup.detector.rows,
                                      std::chrono::seconds(request.timeout_s));
  PlanningResult r = plan_trajectory(acquisition, setup, options, on_view);
  acquisition.finish();
  // The lab's folder is its own: the planned scan names the lab's images from `out`.
  fs::create_directories(request.out);
  for (PlannedViewRecord& v : r.views)
    if (v.acquired)
      v.projection_file = fs::relative(fs::absolute(request.lab / v.projection_file), fs::absolute(request.out)).string();
  return write_planning_run("planned", request.out, std::move(r), setup, true,
                            std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
}

}  // namespace ctk

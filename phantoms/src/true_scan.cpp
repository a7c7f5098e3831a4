#include "ctk/phantoms/true_scan.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <random>
#include <stdexcept>

#include "ctk/core/provenance.hpp"
#include "ctk/phantoms/builtin_phantoms.hpp"

namespace ctk {

namespace {

constexpr double kDegree = M_PI / 180.0;

Eigen::Vector3d gaussian3(std::mt19937_64& rng, double sigma) {
  std::normal_distribution<double> n(0.0, sigma);
  return {n(rng), n(rng), n(rng)};
}

Eigen::Vector3d random_unit_vector(std::mt19937_64& rng) {
  Eigen::Vector3d v;
  do v = gaussian3(rng, 1.0);
  while (v.norm() < 1e-9);
  return v.normalized();
}

// `count` distinct indices out of `n`, in increasing order.
std::vector<int> choose(int n, int count, std::mt19937_64& rng) {
  std::vector<int> all(static_cast<std::size_t>(n));
  std::iota(all.begin(), all.end(), 0);
  std::shuffle(all.begin(), all.end(), rng);
  all.resize(static_cast<std::size_t>(std::clamp(count, 0, n)));
  std::sort(all.begin(), all.end());
  return all;
}

nlohmann::json json3(const Eigen::Vector3d& v) { return {v.x(), v.y(), v.z()}; }
nlohmann::json json2(const Eigen::Vector2d& v) { return {v.x(), v.y()}; }

bool has_pose_effects(const SimulationEffects& e) {
  return e.detector_intrinsics || e.sphere_positions || e.printed_holder || e.robot_base_frame || e.holder_mount ||
         e.joint_offsets_rad || e.source_drift_mm_per_100_views || e.holder_sag_deg || e.source_wobble_mm || e.moving_sphere_mm;
}

void draw_true_holder(const ScanSimulation& sim, TrueScan& truth, std::mt19937_64& rng) {
  truth.holder = sim.holder;
  if (const auto& printed = sim.effects.printed_holder) {
    std::mt19937_64 holder_rng(printed->seed);
    std::normal_distribution<double> n(0.0, printed->sigma_mm);
    for (Eigen::Vector3d& centre : truth.holder.spheres_mm) {
      const Eigen::Vector3d offset(n(holder_rng), n(holder_rng), n(holder_rng));
      centre += offset;
    }
  }
  if (!sim.effects.sphere_positions) return;
  const auto& d = *sim.effects.sphere_positions;
  for (int k : choose(static_cast<int>(sim.holder.spheres_mm.size()), d.count, rng))
    truth.holder.spheres_mm[static_cast<std::size_t>(k)] += d.magnitude_mm * random_unit_vector(rng);
}

// A sphere that comes loose: drawn after the displaced ones, so adding it leaves their draw alone.
void draw_moving_sphere(const ScanSimulation& sim, TrueScan& truth, std::mt19937_64& rng) {
  if (!sim.effects.moving_sphere_mm) return;
  truth.moving_sphere = choose(static_cast<int>(sim.holder.spheres_mm.size()), 1, rng).front();
  truth.moving_sphere_end_mm = *sim.effects.moving_sphere_mm * random_unit_vector(rng);
}

// The holder at view v of n when a sphere moves: its offset grows linearly with the view index.
void place_moving_sphere(TrueScan& truth, TrueView& view, std::size_t v, std::size_t n) {
  if (truth.moving_sphere < 0) return;
  view.holder = truth.holder;
  const double progress = n > 1 ? static_cast<double>(v) / static_cast<double>(n - 1) : 0.0;
  view.holder->spheres_mm[static_cast<std::size_t>(truth.moving_sphere)] += progress * truth.moving_sphere_end_mm;
}

void draw_true_detector(const ScanSimulation& sim, TrueScan& truth, double& true_sdd) {
  const PandaSetup& s = sim.setup;
  true_sdd = s.source_to_detector_mm;
  Eigen::Vector2d pp = s.principal_point_px, tilt(0, 0);
  if (const auto& e = sim.effects.detector_intrinsics) {
    true_sdd += e->sdd_error_mm;
    pp += e->principal_point_error_px;
    tilt = e->tilt_deg * kDegree;
  }
  truth.detector_matrix =
      tilted_detector_matrix(Intrinsics::from_setup(true_sdd, s.detector, pp), true_sdd, s.detector, tilt.x(), tilt.y());
}

void draw_robot_views(const ScanSimulation& sim, TrueScan& truth, double true_sdd, std::mt19937_64& rng) {
  const SimulationEffects& e = sim.effects;
  truth.T_camera_base = sim.setup.T_camera_base * (e.robot_base_frame ? e.robot_base_frame->rigid() : Rigid::Identity());
  truth.T_flange_holder = (e.holder_mount ? e.holder_mount->rigid() : Rigid::Identity()) * sim.setup.T_flange_holder;
  const double sigma_t = sim.robot_noise.translation_mm / std::sqrt(3.0);
  const double sigma_r = sim.robot_noise.rotation_deg * kDegree / std::sqrt(3.0);
  // Two places per target (the thesis' placement experiment): half the separation either way along
  // one direction of the flange frame, drawn once per scan. Drawn only when asked for, so that
  // scans without it keep their random streams.
  Eigen::Vector3d cluster_axis = Eigen::Vector3d::Zero();
  if (e.robot_clusters_mm) cluster_axis = gaussian3(rng, 1.0).normalized() * (0.5 * *e.robot_clusters_mm);
  for (std::size_t v = 0; v < sim.trajectory.size(); ++v) {
    TrueView view;
    view.index = static_cast<int>(v);
    const PlannedView& planned = sim.trajectory[v];
    if (!planned.joints) {
      view.note = planned.note;
      truth.views.push_back(view);
      continue;
    }
    panda::Joints q = *planned.joints;
    if (e.joint_offsets_rad)
      for (std::size_t j = 0; j < q.size(); ++j) q[j] += (*e.joint_offsets_rad)[j];
    view.joints_true = q;
    Rigid noise = make_rigid(rotation_from_vector(gaussian3(rng, sigma_r)), gaussian3(rng, sigma_t));
    if (e.robot_clusters_mm)
      noise.translation() += std::bernoulli_distribution(0.5)(rng) ? cluster_axis : Eigen::Vector3d(-cluster_axis);
    Rigid T_base_flange = panda::forward_kinematics(q);
    // Gravity bends the arm: the flange sinks in proportion to its horizontal reach from the base.
    if (e.robot_droop_mm_per_m)
      T_base_flange.translation().z() -= *e.robot_droop_mm_per_m * 1e-3 * T_base_flange.translation().head<2>().norm();
    Rigid sag = Rigid::Identity();
    if (e.holder_sag_deg) {
      // In flange coordinates: the holder's axis and gravity; it turns about their cross product.
      const Eigen::Vector3d axis = truth.T_flange_holder.linear().col(2);
      const Eigen::Vector3d gravity = T_base_flange.linear().transpose() * Eigen::Vector3d(0, 0, -1);
      const Eigen::Vector3d turn = axis.cross(gravity);  // |turn| = sin(angle to gravity)
      sag = make_rigid(rotation_from_vector(*e.holder_sag_deg * kDegree * turn), Eigen::Vector3d::Zero());
    }
    view.T_camera_holder = truth.T_camera_base * T_base_flange * noise * sag * truth.T_flange_holder;
    if (e.source_drift_mm_per_100_views)
      view.source_offset_mm = drifted_focal_spot_mm(e.source_drift_mm_per_100_views->x(), e.source_drift_mm_per_100_views->y(),
                                                    static_cast<double>(v));
    if (e.source_wobble_mm)
      view.source_offset_mm.head<2>() +=
          *e.source_wobble_mm * std::cos(4 * M_PI * static_cast<double>(v) / static_cast<double>(sim.trajectory.size()));
    place_moving_sphere(truth, view, v, sim.trajectory.size());
    Rigid shift = Rigid::Identity();
    shift.translation() = -view.source_offset_mm;
    view.P = ProjectionMatrix::compose(detector_matrix_for_source_at(truth.detector_matrix, true_sdd, view.source_offset_mm),
                                       shift * *view.T_camera_holder);
    truth.views.push_back(view);
  }
}

void draw_image_effects(const ScanSimulation& sim, TrueScan& truth, std::mt19937_64& rng) {
  std::vector<int> acquired;
  for (const TrueView& v : truth.views)
    if (v.P) acquired.push_back(v.index);
  if (const auto& b = sim.effects.blurred_views) {
    const int count = static_cast<int>(std::lround(b->fraction * static_cast<double>(acquired.size())));
    for (int i : choose(static_cast<int>(acquired.size()), count, rng))
      truth.views[static_cast<std::size_t>(acquired[static_cast<std::size_t>(i)])].blur_sigma_px = b->sigma_px;
  }
  if (const auto& n = sim.effects.false_blobs_per_view) {
    const Detector& d = sim.setup.detector;
    // Blobs look like the holder's spheres: same projected size and peak.
    const double magnification = sim.setup.source_to_detector_mm / sim.setup.source_to_isocentre_mm;
    const double radius_px = 0.5 * sim.holder.sphere_diameter_mm * magnification / d.pitch_u_mm;
    const double peak = material::aluminium * sim.holder.sphere_diameter_mm;
    std::uniform_real_distribution<double> u(0.0, d.cols - 1.0), v(0.0, d.rows - 1.0);
    for (int index : acquired)
      for (int k = 0; k < *n; ++k)
        truth.views[static_cast<std::size_t>(index)].blobs.push_back({u(rng), v(rng), radius_px, peak});
  }
}

}  // namespace

Rigid RigidOffset::rigid() const { return make_rigid(rotation_from_vector(rotation_deg * kDegree), translation_mm); }

int TrueScan::acquired_views() const {
  return static_cast<int>(std::count_if(views.begin(), views.end(), [](const TrueView& v) { return v.P.has_value(); }));
}

TrueScan make_true_scan(const ScanSimulation& sim) {
  if (sim.poses && !sim.trajectory.empty())
    throw std::invalid_argument("simulation: give either a robot trajectory or per-view matrices, not both");
  if (sim.poses && has_pose_effects(sim.effects))
    throw std::invalid_argument("simulation: detector, sphere, robot and drift effects need a robot scan, not given matrices");
  if (sim.supersampling < 1) throw std::invalid_argument("simulation: supersampling must be at least 1");
  std::mt19937_64 rng(sim.seed);
  TrueScan truth;
  draw_true_holder(sim, truth, rng);
  draw_moving_sphere(sim, truth, rng);
  double true_sdd = 0;
  draw_true_detector(sim, truth, true_sdd);
  if (sim.poses) {
    for (std::size_t v = 0; v < sim.poses->views.size(); ++v) {
      const GeometryView& g = sim.poses->views[v];
      TrueView view;
      view.index = static_cast<int>(v);
      if (g.status == ViewStatus::ok)
        view.P = g.P;
      else
        view.note = g.reason.empty() ? "not ok in the given geometry" : g.reason;
      truth.views.push_back(view);
    }
  } else {
    draw_robot_views(sim, truth, true_sdd, rng);
  }
  draw_image_effects(sim, truth, rng);
  return truth;
}

// NOLINTNEXTLINE(readability-function-size): one statement per key of ctk-truth/1, in the file's order
nlohmann::json truth_to_json(const ScanSimulation& sim, const TrueScan& truth, const std::string& geometry_file) {
  const SimulationEffects& e = sim.effects;
  nlohmann::json effects = nlohmann::json::object();
  if (e.detector_intrinsics) {
    const Eigen::Matrix3d& M = truth.detector_matrix;
    // For a tilted detector M is not upper triangular; K is reported as its untilted part.
    const Intrinsics K =
        Intrinsics::from_setup(sim.setup.source_to_detector_mm + e.detector_intrinsics->sdd_error_mm, sim.setup.detector,
                               sim.setup.principal_point_px + e.detector_intrinsics->principal_point_error_px);
    effects["detector_intrinsics"] = {
        {"fu_px", K.fu_px},
        {"fv_px", K.fv_px},
        {"skew_px", K.skew_px},
        {"u0_px", K.u0_px},
        {"v0_px", K.v0_px},
        {"tilt_deg", json2(e.detector_intrinsics->tilt_deg)},
        {"sdd_error_mm", e.detector_intrinsics->sdd_error_mm},
        {"principal_point_error_px", json2(e.detector_intrinsics->principal_point_error_px)},
        {"detector_matrix", {{M(0, 0), M(0, 1), M(0, 2)}, {M(1, 0), M(1, 1), M(1, 2)}, {M(2, 0), M(2, 1), M(2, 2)}}}};
  }
  if (e.detector_distortion)
    effects["detector_distortion"] = {{"k1_per_px2", e.detector_distortion->k1_per_px2},
                                      {"center_px", json2(e.detector_distortion->centre_px)}};
  if (e.sphere_positions || e.printed_holder) {
    nlohmann::json spheres = nlohmann::json::array();
    for (std::size_t k = 0; k < truth.holder.spheres_mm.size(); ++k) {
      const Eigen::Vector3d offset = truth.holder.spheres_mm[k] - sim.holder.spheres_mm[k];
      if (offset.norm() > 0) spheres.push_back({{"index", k}, {"offset_mm", json3(offset)}});
    }
    effects["sphere_positions"] = {{"spheres", spheres}};
    if (e.printed_holder)
      effects["sphere_positions"]["printed_holder"] = {{"sigma_mm", e.printed_holder->sigma_mm},
                                                       {"seed", e.printed_holder->seed}};
  }
  auto rigid_effect = [](const RigidOffset& o) {
    return nlohmann::json{{"translation_mm", json3(o.translation_mm)}, {"rotation_deg", json3(o.rotation_deg)}};
  };
  if (e.robot_base_frame) effects["robot_base_frame"] = rigid_effect(*e.robot_base_frame);
  if (e.holder_mount) effects["holder_mount"] = rigid_effect(*e.holder_mount);
  if (e.joint_offsets_rad) {
    nlohmann::json deg = nlohmann::json::array();
    for (double q : *e.joint_offsets_rad) deg.push_back(q / kDegree);
    effects["joint_offsets"] = {{"offsets_deg", deg}};
  }
  if (e.source_drift_mm_per_100_views) {
    const Eigen::Vector2d mm = *e.source_drift_mm_per_100_views;
    effects["source_drift"] = {
        {"drift_mm_per_100_views", json2(mm)},
        {"drift_px_per_100_views", {mm.x() / sim.setup.detector.pitch_u_mm, mm.y() / sim.setup.detector.pitch_v_mm}}};
  }
  if (e.holder_sag_deg) effects["holder_sag"] = {{"max_deg", *e.holder_sag_deg}};
  if (e.source_wobble_mm) effects["source_wobble"] = {{"amplitude_mm", json2(*e.source_wobble_mm)}};
  if (truth.moving_sphere >= 0)
    effects["moving_sphere"] = {{"index", truth.moving_sphere}, {"offset_at_last_view_mm", json3(truth.moving_sphere_end_mm)}};
  if (e.blurred_views) {
    nlohmann::json views = nlohmann::json::array();
    for (const TrueView& v : truth.views)
      if (v.blur_sigma_px > 0) views.push_back(v.index);
    effects["blurred_views"] = {{"sigma_px", e.blurred_views->sigma_px}, {"views", views}};
  }
  {
    nlohmann::json nuisances = nlohmann::json::object();
    const std::pair<const char*, const std::optional<double>*> named[] = {
        {"scatter_fraction", &e.scatter_fraction},   {"detector_psf_px", &e.detector_psf_px},
        {"focal_spot_mm", &e.focal_spot_mm},         {"detector_lag", &e.detector_lag},
        {"robot_clusters_mm", &e.robot_clusters_mm}, {"robot_droop_mm_per_m", &e.robot_droop_mm_per_m}};
    for (const auto& [key, value] : named)
      if (*value) nuisances[key] = **value;
    if (!nuisances.empty()) effects["lab_nuisances"] = nuisances;
  }
  if (e.false_blobs_per_view) {
    nlohmann::json blobs = nlohmann::json::array();
    for (const TrueView& v : truth.views)
      for (const Blob& b : v.blobs)
        blobs.push_back({{"view", v.index}, {"u_px", b.u_px}, {"v_px", b.v_px}, {"radius_px", b.radius_px}, {"peak", b.peak}});
    effects["false_blobs"] = {{"per_view", *e.false_blobs_per_view}, {"blobs", blobs}};
  }

  nlohmann::json views = nlohmann::json::array();
  for (const TrueView& v : truth.views) {
    nlohmann::json j = {{"index", v.index}, {"acquired", v.P.has_value()}};
    if (!v.note.empty()) j["note"] = v.note;
    if (v.joints_true) j["joints_true_rad"] = *v.joints_true;
    if (v.T_camera_holder) j["T_camera_holder"] = rigid_to_json(*v.T_camera_holder);
    if (v.source_offset_mm.norm() > 0) j["source_offset_mm"] = json3(v.source_offset_mm);
    views.push_back(j);
  }
  nlohmann::json spheres = nlohmann::json::array();
  for (const auto& s : truth.holder.spheres_mm) spheres.push_back(json3(s));

  return {
      {"format", "ctk-truth/1"},
      {"provenance", provenance()},
      {"geometry", geometry_file},
      {"effects", effects},
      {"conventions",
       {{"robot_base_frame", "true T_camera_base = declared T_camera_base * offset (offset in base coordinates)"},
        {"holder_mount", "true T_flange_holder = offset * declared T_flange_holder (offset in flange coordinates)"},
        {"joint_offsets", "true joint angle = logged angle + offset"},
        {"source_drift", "focal spot at view v displaced by v / 100 * drift in camera x, y; detector fixed"},
        {"detector_distortion", "ideal projection x is measured at x + k1 |x - c|^2 (x - c)"},
        {"robot_noise", "per view, between FK(joints) and the flange: Gaussian, each axis value / sqrt(3)"},
        {"holder_sag",
         "the holder turns about the flange origin by max_deg * (axis x gravity), flange coordinates, gravity -z of the base"},
        {"source_wobble",
         "focal spot at view v of n displaced by amplitude * cos(4 pi v / n) in camera x, y, on top of any drift"},
        {"moving_sphere",
         "sphere `index` is at its true place plus (v / (n - 1)) * offset_at_last_view at view v of n (holder frame)"}}},
      {"robot_noise", {{"translation_mm", sim.robot_noise.translation_mm}, {"rotation_deg", sim.robot_noise.rotation_deg}}},
      {"simulation",
       {{"supersampling", sim.supersampling},
        {"output", sim.output == SimulatedOutput::counts ? "counts" : "line_integrals"},
        {"flat_counts", sim.counts.flat_counts},
        {"dark_counts", sim.counts.dark_counts},
        {"seed", sim.seed},
        {"holder_in_beam", sim.with_holder},
        {"sample", sim.sample.name},
        {"spectrum", sim.spectrum ? nlohmann::json{{"kvp", sim.spectrum->kvp},
                                                   {"filter_al_mm", sim.spectrum->filter_al_mm},
                                                   {"mean_energy_kev", sim.spectrum->mean_energy_kev()},
                                                   {"bins", sim.spectrum->bins.size()}}
                                  : nlohmann::json("monochromatic")}}},
      {"holder_spheres_mm", spheres},
      {"views", views}};
}

Geometry true_geometry(const ScanSimulation& sim, const TrueScan& truth, const std::vector<std::string>& names) {
  Geometry g;
  g.detector = sim.setup.detector;
  for (const TrueView& v : truth.views) {
    GeometryView view;
    view.index = v.index;
    view.projection = names.at(static_cast<std::size_t>(v.index));
    view.status = v.P ? ViewStatus::ok : ViewStatus::skipped;
    view.reason = v.note;
    view.P = v.P;
    g.views.push_back(view);
  }
  return g;
}

}  // namespace ctk

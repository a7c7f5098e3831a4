#include "ctk/plan/plan_trajectory.hpp"

#include <algorithm>
#include <chrono>
#include <numeric>
#include <optional>

#include "ctk/core/error.hpp"
#include "ctk/geom/trajectory.hpp"
#include "ctk/measure/projection_reading.hpp"
#include "ctk/plan/planner_picture.hpp"

namespace ctk {

namespace {

using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

DamageGeometry damage_geometry(const PandaSetup& setup) {
  DamageGeometry g;
  g.source_to_isocentre_mm = setup.source_to_isocentre_mm;
  g.source_to_detector_mm = setup.source_to_detector_mm;
  return g;
}

// The scout's requests in order until `full()`. A direction that is refused is asked again from the
// opposite side: it sees nearly the same lines, and the robot may reach it (or its spheres may fix
// the pose). `take` requests one direction and says whether it was taken.
void request_scout(int nside, const std::function<bool(const Eigen::Vector3d&)>& take, const std::function<bool()>& full) {
  for (const Eigen::Vector3d& d : scout_directions(nside)) {
    if (full()) return;
    if (!take(d) && !full()) take(-d);
  }
}

class Loop {
 public:
  Loop(Acquisition& acquisition, const PlanningSetup& setup, const PlanningOptions& options)
      : acq_(acquisition),
        s_(setup),
        o_(options),
        planner_(options.planner),
        recon_(options.coarse_volume, setup.setup.detector, options.reconstruction),
        K_(Intrinsics::from_setup(setup.setup.source_to_detector_mm, setup.setup.detector, setup.setup.principal_point_px)) {}

  // Requests one view; returns the record (planner time of the bookkeeping included).
  PlannedViewRecord take(const Eigen::Vector3d& direction, bool scout, double damage_mm) {
    PlannedViewRecord rec;
    rec.index = next_index_++;
    rec.scout = scout;
    rec.requested = direction.normalized();
    rec.damage_mm = damage_mm;
    AcquisitionRequest request{rec.index, rec.requested, rotation_looking_along(rec.requested),
                               Eigen::Vector3d(0, 0, s_.setup.source_to_isocentre_mm)};
    AcquisitionAnswer answer = acq_.acquire(request);
    const auto start = Clock::now();
    if (!answer.acquired) {
      rec.reason = answer.reason.empty() ? "unreachable" : answer.reason;
      planner_.record_unreachable(rec.requested);
      rec.planning_seconds = seconds_since(start);
      return rec;
    }
    rec.acquired = true;
    rec.joints = answer.joints;
    rec.projection_file = answer.projection_file;
    const Detector& d = s_.setup.detector;
    const std::size_t n = static_cast<std::size_t>(d.cols) * static_cast<std::size_t>(d.rows);
    Image p{d.cols, d.rows, std::vector<float>(n)}, w{d.cols, d.rows, std::vector<float>(n)};
    std::size_t clamped = 0;
    counts_to_line_integrals(answer.counts, s_.flat, s_.dark, p.pixels.data(), w.pixels.data(), clamped);
    const Rigid guess = s_.setup.T_camera_base * panda::forward_kinematics(answer.joints) * s_.setup.T_flange_holder;
    const ViewCalibration cal = calibrate_view(p, K_.K(), guess, s_.holder, d, o_.calibration);
    if (cal.status != ViewStatus::ok || !cal.P) {
      // The robot's pose is a millimetre off (its base is never where the setup says): such a
      // view would blur the reconstruction, so it is kept out and the planner draws another
      // direction, away from this one.
      rec.reason = "calibration failed: " + cal.reason;
      planner_.record_unreachable(rec.requested);
      rec.planning_seconds = seconds_since(start);
      return rec;
    }
    rec.calibrated = true;
    rec.P = *cal.P;
    rec.calibration_rms_px = cal.rms_px;
    recon_.add_view(*rec.P, p, w);
    planner_.record_acquired(rec.P->principal_ray());
    ++calibrated_;
    rec.planning_seconds = seconds_since(start);
    return rec;
  }

  // Reconstruct, segment, score: the planner's picture after the views so far.
  double refresh() {
    const auto start = Clock::now();
    recon_.update();
    picture_ = read_planner_picture(recon_.volume(), planner_.candidates(), o_.picture_reading(), damage_geometry(s_.setup));
    picture_.give_to(planner_);
    return seconds_since(start);
  }

  PlanningResult run(const std::function<void(const PlannedViewRecord&)>& on_view) {
    PlanningResult result;
    auto report = [&](PlannedViewRecord rec) {
      if (on_view) on_view(rec);
      result.views.push_back(std::move(rec));
    };
    const int max_attempts = o_.request_limit();
    if (!o_.fixed_directions.empty()) {
      for (const Eigen::Vector3d& d : o_.fixed_directions) {
        if (calibrated_ >= o_.views || next_index_ >= max_attempts) break;
        report(take(d, false, 0));
      }
      refresh();
      return finish(std::move(result));
    }
    request_scout(
        o_.scout_nside,
        [&](const Eigen::Vector3d& d) {
          PlannedViewRecord rec = take(d, true, 0);
          const bool taken = rec.calibrated;
          report(std::move(rec));
          return taken;
        },
        [&] { return calibrated_ >= o_.views; });
    result.views.back().planning_seconds += refresh();
    while (calibrated_ < o_.views && next_index_ < max_attempts) {
      const auto start = Clock::now();
      const std::optional<Eigen::Vector3d> next = planner_.next();
      if (!next) break;
      const auto cell = static_cast<std::size_t>(HealpixSphere(o_.planner.candidate_nside).cell_of(*next));
      const double chosen = seconds_since(start);
      PlannedViewRecord rec = take(*next, false, picture_.damage_mm.empty() ? 0.0 : picture_.damage_mm[cell]);
      rec.planning_seconds += chosen;
      if (rec.calibrated) rec.planning_seconds += refresh();
      result.step_seconds.push_back(rec.planning_seconds);
      report(std::move(rec));
    }
    return finish(std::move(result));
  }

  PlanningResult finish(PlanningResult result) {
    result.coarse = recon_.volume();
    result.segmentation = picture_.segmentation;
    result.candidates = planner_.candidates();
    result.weights = planner_.weights();
    result.damage_mm = picture_.damage_mm;
    result.planner = o_.planner;
    result.edge_tangency = o_.edge_tangency;
    result.picture_median = o_.picture_median;
    return result;
  }

 private:
  Acquisition& acq_;
  const PlanningSetup& s_;
  const PlanningOptions& o_;
  ViewPlanner planner_;
  IncrementalReconstruction recon_;
  Intrinsics K_;
  PlannerPicture picture_;
  int next_index_ = 0, calibrated_ = 0;
};

}  // namespace

int PlanningResult::acquired() const {
  return static_cast<int>(std::count_if(views.begin(), views.end(), [](const PlannedViewRecord& v) { return v.acquired; }));
}

double PlanningResult::mean_step_seconds() const {
  if (step_seconds.empty()) return 0;
  return std::accumulate(step_seconds.begin(), step_seconds.end(), 0.0) / static_cast<double>(step_seconds.size());
}

double PlanningResult::max_step_seconds() const {
  return step_seconds.empty() ? 0.0 : *std::max_element(step_seconds.begin(), step_seconds.end());
}

int PlanningResult::calibrated() const {
  return static_cast<int>(std::count_if(views.begin(), views.end(), [](const PlannedViewRecord& v) { return v.calibrated; }));
}

std::vector<Eigen::Vector3d> plan_on_picture(const Volume& picture, const PlanningOptions& options,
                                             const DamageGeometry& geometry,
                                             const std::function<bool(const Eigen::Vector3d&)>& reachable) {
  options.validate();
  ViewPlanner planner(options.planner);
  read_planner_picture(picture, planner.candidates(), options.picture_reading(), geometry).give_to(planner);
  std::vector<Eigen::Vector3d> taken;
  int requests = 0;
  const auto take = [&](const Eigen::Vector3d& d) {
    ++requests;
    const bool ok = !reachable || reachable(d);
    if (ok) {
      taken.push_back(d);
      planner.record_acquired(d);
    } else {
      planner.record_unreachable(d);
    }
    return ok;
  };
  const auto wanted = static_cast<std::size_t>(options.views);
  request_scout(options.scout_nside, take, [&] { return taken.size() >= wanted; });
  while (taken.size() < wanted && requests < options.request_limit()) {
    const std::optional<Eigen::Vector3d> next = planner.next();
    if (!next) break;
    take(*next);
  }
  return taken;
}

// HEALPix cells come in opposite pairs; the scout keeps the cell of each pair whose first non-zero
// coordinate, from z down to x, is positive.
std::vector<Eigen::Vector3d> scout_directions(int nside) {
  std::vector<Eigen::Vector3d> half;
  for (const Eigen::Vector3d& d : HealpixSphere(nside).directions()) {
    const double tie = 1e-9;
    const double key = std::abs(d.z()) > tie ? d.z() : std::abs(d.y()) > tie ? d.y() : d.x();
    if (key > 0) half.push_back(d);
  }
  return half;
}

// Once every line is taken, the opposites follow, spread as directions.
std::vector<Eigen::Vector3d> whole_sphere_order(int nside) {
  const std::vector<Eigen::Vector3d> cells = HealpixSphere(nside).directions();
  std::vector<Eigen::Vector3d> order;
  std::vector<double> line(cells.size(), 4.0), direction(cells.size(), 4.0);  // to the chosen ones
  const auto farther = [&](std::size_t c, std::size_t b) {
    if (line[c] != line[b] || line[c] > 0) return line[c] > line[b];
    return direction[c] > direction[b];
  };
  std::size_t pick = 0;
  while (order.size() < cells.size()) {
    order.push_back(cells[pick]);
    std::optional<std::size_t> best;  // among the cells not chosen yet: those a direction away
    for (std::size_t c = 0; c < cells.size(); ++c) {
      line[c] = std::min(line[c], line_distance_rad(cells[c], cells[pick]));
      direction[c] = std::min(direction[c], angular_distance_rad(cells[c], cells[pick]));
      if (direction[c] > 0 && (!best || farther(c, *best))) best = c;
    }
    if (best) pick = *best;
  }
  return order;
}

PictureReading PlanningOptions::picture_reading() const {
  return {segmentation, edge_tangency, planner.edge_tangency_weight > 0, picture_median};
}

void PlanningOptions::validate() const {
  require_option(scout_nside >= 1, "PlanningOptions.scout_nside", "a HEALPix nside of at least 1", scout_nside);
  require_option(views >= 1, "PlanningOptions.views", "at least 1", views);
  require_option(max_attempts >= 0, "PlanningOptions.max_attempts", "0 (three times views) or more", max_attempts);
  for (int a = 0; a < 3; ++a) {
    require_option(coarse_volume.size[static_cast<std::size_t>(a)] >= 1, "PlanningOptions.coarse_volume.size",
                   "at least 1 voxel per axis", coarse_volume.size[static_cast<std::size_t>(a)]);
    require_option(coarse_volume.voxel_mm[a] > 0, "PlanningOptions.coarse_volume.voxel_mm", "a number above 0",
                   coarse_volume.voxel_mm[a]);
  }
  planner.validate();
  reconstruction.validate();
  segmentation.validate();
  edge_tangency.validate();
  calibration.validate();
}

PlanningResult plan_trajectory(Acquisition& acquisition, const PlanningSetup& setup, const PlanningOptions& options,
                               const std::function<void(const PlannedViewRecord&)>& on_view) {
  options.validate();
  return Loop(acquisition, setup, options).run(on_view);
}

}  // namespace ctk

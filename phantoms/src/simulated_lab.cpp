#include "ctk/phantoms/simulated_lab.hpp"

#include <stdexcept>

namespace ctk {

SimulatedLab::SimulatedLab(ScanSimulation simulation) : sim_(std::move(simulation)) {
  if (sim_.effects.sphere_positions)
    throw std::invalid_argument("simulated lab: displaced spheres are drawn per scan; give them as a holder instead");
  sim_.trajectory.clear();
  sim_.poses.reset();
  // The truth that does not change from shot to shot (holder, detector): one view's worth.
  ScanSimulation probe = sim_;
  probe.trajectory = {PlannedView{}};
  phantom_ = simulated_phantom(sim_, make_true_scan(probe).holder);
  render_ = simulated_render_options(sim_);
}

LabShot SimulatedLab::take(const Eigen::Vector3d& direction) {
  const int shot = shots_++;
  LabShot out;
  const PlannedView planned = spherical_robot_trajectory(sim_.setup, {direction.normalized()}).front();
  if (!planned.joints) {
    out.note = planned.note;
    return out;
  }
  ScanSimulation one = sim_;
  one.trajectory = {planned};
  one.seed = sim_.seed * 1000003ULL + static_cast<std::uint64_t>(shot);  // robot and photon noise per shot
  TrueScan truth = make_true_scan(one);
  TrueView& view = truth.views.front();
  out.reached = true;
  out.joints = *planned.joints;
  out.true_P = view.P;
  out.image = simulated_image(one, phantom_, view, render_);
  return out;
}

}  // namespace ctk

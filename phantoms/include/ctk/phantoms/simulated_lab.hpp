#pragma once
// A lab in software for the view planner: asked for a holder orientation, it runs the arm's IK
// (joint limits only), puts the holder where the true setup and the robot's repeatability put it,
// and exposes a projection of the phantom — or answers that the arm cannot reach the orientation.
// Each shot draws its own robot noise and photon noise from (seed, shot number).
#include <optional>
#include <string>

#include "ctk/phantoms/scan_simulation.hpp"

namespace ctk {

struct LabShot {
  bool reached = false;
  std::string note;        // why not
  panda::Joints joints{};  // as logged
  Image image;             // counts (or line integrals, per the simulation's output)
  std::optional<ProjectionMatrix> true_P;
};

class SimulatedLab {
 public:
  /// `simulation.trajectory` and `poses` are ignored; effects that differ per scan draw
  /// (displaced spheres) are refused with std::invalid_argument.
  explicit SimulatedLab(ScanSimulation simulation);

  LabShot take(const Eigen::Vector3d& direction);
  const ScanSimulation& simulation() const { return sim_; }
  int shots() const { return shots_; }

 private:
  ScanSimulation sim_;
  Phantom phantom_;
  RenderOptions render_;
  int shots_ = 0;
};

}  // namespace ctk

#pragma once
// The simulated lab as the view planner's acquisition side (target ctk::plan_simulated, the only
// part of libplan that knows the simulator): each request becomes a shot;
// its counts are written as a TIFF in `folder` (when given) under the name the planned scan will
// use, and its true matrix is kept for whoever checks the calibration.
#include <filesystem>
#include <map>
#include <optional>

#include "ctk/phantoms/simulated_lab.hpp"
#include "ctk/plan/plan_trajectory.hpp"

namespace ctk {

class SimulatedAcquisition final : public Acquisition {
 public:
  explicit SimulatedAcquisition(SimulatedLab& lab, std::optional<std::filesystem::path> folder = std::nullopt);
  AcquisitionAnswer acquire(const AcquisitionRequest& request) override;
  /// True matrix of each acquired request.
  const std::map<int, ProjectionMatrix>& true_matrices() const { return truth_; }

 private:
  SimulatedLab& lab_;
  std::optional<std::filesystem::path> folder_;
  std::map<int, ProjectionMatrix> truth_;
};

/// What the planner is told about a simulated setup: the declared geometry and holder, and the
/// open-beam frames.
PlanningSetup planning_setup(const ScanSimulation& simulation);

}  // namespace ctk

#pragma once
// What the final model of a diagnosis leaves unexplained, tested against the noise: residual
// groups (by sphere, by detector region), spheres whose residuals follow the scan's progress, and
// in the robot channel deviations that change smoothly with the view order, follow the direction
// of gravity, or exceed the repeatability. Each finding says where and what, in words for the report.
#include <string>
#include <vector>

#include "ctk/calib/scan_model.hpp"
#include "ctk/calib/scan_model_fit.hpp"

namespace ctk {

struct StructureFinding {
  std::string where;  // "by sphere", "by detector region", "by sphere over the scan", "by view order", "by robot configuration"
  std::string what;
};

/// The structure the fit `f` of every view of `observations` leaves; empty when the residuals are
/// consistent with detection noise and the robot's repeatability.
std::vector<StructureFinding> find_structure(const ScanObservations& observations, const ScanModelFit& f);

}  // namespace ctk

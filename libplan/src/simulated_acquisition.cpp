#include "ctk/plan/simulated_acquisition.hpp"

#include <cstdio>

namespace ctk {

SimulatedAcquisition::SimulatedAcquisition(SimulatedLab& lab, std::optional<std::filesystem::path> folder)
    : lab_(lab), folder_(std::move(folder)) {
  if (folder_) std::filesystem::create_directories(*folder_ / "projections");
}

AcquisitionAnswer SimulatedAcquisition::acquire(const AcquisitionRequest& r) {
  LabShot shot = lab_.take(r.direction);
  AcquisitionAnswer a;
  if (!shot.reached) {
    a.reason = shot.note;
    return a;
  }
  char name[64];
  std::snprintf(name, sizeof name, "projections/proj_%04d.tif", r.view);
  if (folder_) write_image_uint16(shot.image, *folder_ / name);
  a.acquired = true;
  a.joints = shot.joints;
  a.counts = std::move(shot.image);
  a.projection_file = name;
  if (shot.true_P) truth_.emplace(r.view, *shot.true_P);
  return a;
}

PlanningSetup planning_setup(const ScanSimulation& sim) {
  OpenBeamFrames frames = open_beam_frames(sim);
  return {sim.setup, sim.holder, std::move(frames.flat), std::move(frames.dark)};
}

}  // namespace ctk

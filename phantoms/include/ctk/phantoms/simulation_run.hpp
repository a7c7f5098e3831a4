#pragma once
// The simulation workflow: a scan folder from a request a person writes (phantom names, a
// trajectory by name, the detector, noise, the undeclared effects by name), with its truth beside
// it. The folder is written whole and swapped in at the end, and a folder holding a scan no
// simulation wrote is refused. `ctk simulate` and `ctk.simulate` wrap it.
#include <cstdint>
#include <filesystem>
#include <functional>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "ctk/geom/geometry_file.hpp"
#include "ctk/phantoms/scan_simulation.hpp"
#include "ctk/phantoms/simulation_config.hpp"

namespace ctk {

struct SimulationRequest {
  /// Built-in phantom names (helix-holder, shepp-logan, ...) or ctk-phantom/1 files (.json).
  std::vector<std::string> phantoms{"helix-holder"};
  /// The holder the scan declares and "helix-holder" draws: a built-in one by name (reference,
  /// thesis-first) or a ctk-holder/1 file.
  std::string holder = "reference";
  /// circular (joint-7 orbit), spherical (HEALPix directions), cap (a band of directions about
  /// the holder axis while it spins), random (uniform directions from the seed); ignored with poses.
  std::string trajectory = "circular";
  int views = 360;                           // circular, cap, random
  int nside = 3;                             // spherical: 12 nside^2 directions
  double cap_min_deg = 5, cap_max_deg = 90;  // cap: angles between beam and holder axis
  std::filesystem::path poses;               // a ctk-geometry/1 file of matrices instead of a robot trajectory
  int cols = 720, rows = 720;
  double pitch_mm = 0.6, sdd_mm = 2150.0, sod_mm = 1360.0;
  int supersampling = 2;
  SimulatedOutput output = SimulatedOutput::counts;
  CountsModel counts;
  std::optional<double> kvp;  // polychromatic from a tube at this voltage
  double filter_al_mm = 2.0;
  RobotNoise robot_noise;
  std::uint64_t seed = 1;
  SimulationEffects effects;
  void validate() const;  // std::invalid_argument naming the field
};

struct SimulationRun {
  SimulationReport report;
  std::filesystem::path scan_file;  // <out>/scan.json
  std::string in_the_beam;          // "helix-holder + walnut"
  int cols = 0, rows = 0;
  double seconds = 0;
  /// "simulated scan written to ...: N views (n acquired, m unreachable), C x R px, phantom: ..."
  std::string brief() const;
};

/// The undeclared effects by the names `ctk simulate` gives them (without the dashes, '-' as
/// '_'): {"base_translation_mm": [0, 0, 1.3], "distortion_k1": 2e-8, ...}. Throws
/// std::invalid_argument naming an unknown key or a value of the wrong length; a distortion
/// centre defaults to the detector's.
SimulationEffects simulation_effects_from_json(const nlohmann::json& named, const Detector& detector);

/// Writes the scan into `out`. `log` receives warnings and steps (the IK planning of a spherical
/// trajectory), `progress(done, total)` the views written. Throws InputError naming `out` when
/// it holds a scan that no simulation wrote, or a phantom file that cannot be read.
SimulationRun run_simulation(const SimulationRequest& request, const std::filesystem::path& out,
                             const std::function<void(int, int)>& progress = {},
                             const std::function<void(const std::string&)>& log = {});

}  // namespace ctk

#pragma once
// Everything a simulated scan is made from: the nominal setup the scan file will declare, what
// is in the beam, the trajectory, the detector, and the effects that make the truth differ from
// the declaration. Every effect is off unless set; each one set is written to truth.json.
#include <cstdint>
#include <optional>

#include "ctk/geom/geometry_file.hpp"
#include "ctk/geom/helix.hpp"
#include "ctk/geom/panda_setup.hpp"
#include "ctk/phantoms/detector_response.hpp"
#include "ctk/phantoms/phantom.hpp"
#include "ctk/phantoms/robot_trajectory.hpp"
#include "ctk/phantoms/xray_spectrum.hpp"

namespace ctk {

/// A small rigid error: translation (mm) and rotation vector (degrees).
struct RigidOffset {
  Eigen::Vector3d translation_mm{0, 0, 0};
  Eigen::Vector3d rotation_deg{0, 0, 0};
  Rigid rigid() const;
};

struct DetectorIntrinsicsError {
  double sdd_error_mm = 0;                         // true SDD = declared + error
  Eigen::Vector2d principal_point_error_px{0, 0};  // true (u0, v0) = declared + error
  Eigen::Vector2d tilt_deg{0, 0};                  // out-of-plane: about u, then about v
};

struct SphereDisplacement {
  int count = 5;              // how many spheres (chosen at random) are off
  double magnitude_mm = 0.2;  // each by this much, in a random direction
};

/// A 3-D printed holder: every sphere off its declared centre by a Gaussian of this sigma per
/// axis, drawn from a seed of the holder's own, so that the scans of one holder (each with its own
/// seed) share it.
struct PrintedHolder {
  double sigma_mm = 0.1;
  std::uint64_t seed = 1;
};

struct BlurredViews {
  double fraction = 0.05;  // of the acquired views, chosen at random
  double sigma_px = 2.0;
};

/// Conventions (also written to truth.json): the true base pose is T_camera_base * offset (offset
/// in base coordinates); the true mount is offset * T_flange_holder (offset in flange
/// coordinates); the true joint angle is the logged one plus its offset; the focal spot moves
/// linearly with the view index, starting at zero.
struct SimulationEffects {
  std::optional<DetectorIntrinsicsError> detector_intrinsics;
  std::optional<RadialDistortion> detector_distortion;
  std::optional<SphereDisplacement> sphere_positions;
  std::optional<PrintedHolder> printed_holder;  // reported under sphere_positions too
  std::optional<RigidOffset> robot_base_frame;
  std::optional<RigidOffset> holder_mount;
  std::optional<panda::Joints> joint_offsets_rad;
  std::optional<Eigen::Vector2d> source_drift_mm_per_100_views;  // camera x, y
  /// Outside the diagnosis' vocabulary: the holder bends under its weight, turning about the
  /// flange towards gravity (-z of the robot base) by this angle times the sine of the angle
  /// between its axis and gravity (a cantilever's load), so the error depends on the orientation.
  std::optional<double> holder_sag_deg;
  /// Outside the vocabulary: the focal spot wanders as amplitude * cos(4 pi v / views) in camera
  /// x, y (mm): two periods over the scan, no mean and no linear trend for an offset or a drift to
  /// take up, nor the once-per-turn pattern of a mount offset on a joint-7 orbit.
  std::optional<Eigen::Vector2d> source_wobble_mm;
  /// Outside the vocabulary: one sphere (drawn at random) comes loose and moves in a random
  /// direction, from its declared place at the first view to this far (mm) at the last.
  std::optional<double> moving_sphere_mm;
  std::optional<BlurredViews> blurred_views;
  std::optional<int> false_blobs_per_view;
  /// A real lab's nuisances, which no effect of the diagnosis names and none may be reported for
  /// (counts output only; the robot ones for any output):
  std::optional<double> scatter_fraction;      // smooth background: this fraction of the flat times the blurred transmission
  std::optional<double> detector_psf_px;       // Gaussian PSF of the detector (sigma, px) on the intensities
  std::optional<double> focal_spot_mm;         // focal spot FWHM: a Gaussian penumbra scaled by the magnification less one
  std::optional<double> detector_lag;          // this fraction of the previous view's signal stays in the next
  std::optional<double> robot_clusters_mm;     // the flange lands in one of two places per target, this far apart
  std::optional<double> robot_droop_mm_per_m;  // the flange sinks this much per metre of horizontal reach (gravity)
};

/// Pose repeatability between the joints' forward kinematics and where the flange really is:
/// RMS of the 3-D translation and of the rotation angle (each axis gets value / sqrt(3)).
struct RobotNoise {
  double translation_mm = 0.1;
  double rotation_deg = 0.02;
};

enum class SimulatedOutput { counts, line_integrals };

struct ScanSimulation {
  PandaSetup setup;                     // the nominal setup the scan file declares
  Holder holder;                        // the declared holder
  bool with_holder = true;              // the helix holder in the beam (true spheres)
  Phantom sample;                       // anything else in the beam, holder frame
  std::vector<PlannedView> trajectory;  // a robot scan ...
  std::optional<Geometry> poses;        // ... or given per-view matrices (no robot, no pose effects)
  int supersampling = 2;
  /// Polychromatic rays (beam hardening, photon starvation behind dense parts); absent:
  /// monochromatic at the reference energy.
  std::optional<XraySpectrum> spectrum;
  SimulatedOutput output = SimulatedOutput::counts;
  CountsModel counts;
  RobotNoise robot_noise;
  SimulationEffects effects;
  std::uint64_t seed = 1;
};

}  // namespace ctk

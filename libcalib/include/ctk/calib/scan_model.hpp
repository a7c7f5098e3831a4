#pragma once
// The physical model of a whole scan that the diagnosis refits: the declared setup plus the
// named effects of the diagnosis contract (diagnosis-report.md), each a small set of parameters
// that is zero when the effect is absent, and the observations the model must explain (every
// calibrated view's matched sphere centres and, for robot scans, its logged joints).
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
#include <optional>
#include <string>
#include <vector>

#include "ctk/calib/scan_calibration.hpp"
#include "ctk/geom/detector.hpp"
#include "ctk/geom/helix.hpp"
#include "ctk/geom/panda.hpp"
#include "ctk/geom/rigid.hpp"
#include "ctk/geom/scan.hpp"

namespace ctk {

enum class Effect {
  robot_base_frame,
  holder_mount,
  joint_offsets,
  source_drift,
  sphere_positions,
  detector_distortion,
  detector_intrinsics,
  gravity_load  // outside the contract's vocabulary: a competitor, never an accepted effect
};
/// In the order used to choose among effects that explain the same residual equally well: the
/// robot's frames first (they are never where the setup says), the detector last (a lab measures
/// it separately and it rarely changes).
inline constexpr std::array<Effect, 7> kEffects{Effect::robot_base_frame,   Effect::holder_mount,     Effect::joint_offsets,
                                                Effect::source_drift,       Effect::sphere_positions, Effect::detector_distortion,
                                                Effect::detector_intrinsics};
/// Loads the contract has no name for, which the diagnosis still fits beside the vocabulary so
/// that a holder bending under gravity is found as what it is and not reported as a frame offset
/// that explains part of it.
inline constexpr std::array<Effect, 1> kOutsideEffects{Effect::gravity_load};
/// Everything the scan model can fit: the vocabulary, then the loads outside it.
inline constexpr std::array<Effect, kEffects.size() + kOutsideEffects.size()> kModelledEffects{
    Effect::robot_base_frame, Effect::holder_mount,        Effect::joint_offsets,       Effect::source_drift,
    Effect::sphere_positions, Effect::detector_distortion, Effect::detector_intrinsics, Effect::gravity_load};
const char* effect_name(Effect e);
/// Effects that act through the robot's kinematics need a robot pose source.
bool needs_robot(Effect e);

/// Every effect's parameters; all zero is the declared setup.
struct EffectParameters {
  double base[6] = {0, 0, 0, 0, 0, 0};       // rotation vector (rad), translation (mm); base coordinates
  double mount[6] = {0, 0, 0, 0, 0, 0};      // same, flange coordinates
  double joints[7] = {0, 0, 0, 0, 0, 0, 0};  // true angle = logged + offset (rad)
  double drift[2] = {0, 0};                  // focal spot offset per 100 views, camera x and y (mm)
  double intrinsics[3] = {0, 0, 0};          // principal point shift u, v (px); focal length change (px, on fu and fv alike)
  double distortion[3] = {0, 0, 0};  // radial shift at 360 px from the centre (px); centre offset from the principal point (px)
  double gravity[2] = {0, 0};        // holder's turn (rad) and shift (mm) under gravity across its axis (gravity_load_offset)
  std::vector<Eigen::Vector3d> spheres;  // offset of each sphere (mm, holder frame)
  /// Which sphere offsets are free when sphere_positions is fitted: empty or all true means all
  /// (the list's centroid, orientation and scale then fixed by a gauge); a subset is held in place
  /// by the rest.
  std::vector<bool> free_spheres;
};

/// The holder's pose change under its own weight, flange coordinates, as a rotation vector and a
/// translation: it turns about a x g by gravity[0] and shifts along g - (g.a) a by gravity[1],
/// where a is the holder's axis and g the unit downward direction (base -z), both in the flange
/// frame. Both scale with the sine of the axis's angle to the vertical, as a cantilever's
/// deflection does; the pair covers a turn about any point of the axis.
template <typename T>
Eigen::Matrix<T, 6, 1> gravity_load_offset(const Eigen::Matrix<T, 3, 3>& R_base_flange, const Eigen::Vector3d& holder_axis,
                                           const T* gravity) {
  const Eigen::Matrix<T, 3, 1> g = -R_base_flange.row(2).transpose();
  // For Jets a conversion, for double a copy of three numbers.
  // NOLINTNEXTLINE(performance-unnecessary-copy-initialization)
  const Eigen::Matrix<T, 3, 1> a = holder_axis.cast<T>();
  Eigen::Matrix<T, 6, 1> x;
  x.template head<3>() = gravity[0] * a.cross(g);
  x.template tail<3>() = gravity[1] * (g - g.dot(a) * a);
  return x;
}

/// The kinematic chain and detector the scan declares.
struct DeclaredSetup {
  Intrinsics K;
  Detector detector;
  Holder holder;
  bool robot = false;
  Rigid T_camera_base = Rigid::Identity(), T_flange_holder = Rigid::Identity();
  Eigen::Vector2d source_drift_mm_per_100_views{0, 0};  // declared; the source_drift effect adds to it
};

struct ViewObservations {
  int view = 0;  // projection index (time order)
  std::optional<panda::Joints> joints;
  Rigid T_calibrated;  // the per-view calibrated pose (start of every fit)
  std::vector<int> spheres;
  std::vector<Eigen::Vector2d> measured_px;
  double centre_sigma_px = 0;  // this view's own detection noise; 0: the scan's
};

struct ScanObservations {
  DeclaredSetup setup;
  std::vector<ViewObservations> views;
  double centre_sigma_px = 0.05;  // detection noise per axis, from the calibration residuals
  double robot_sigma_mm = 0.1;    // robot repeatability (per view, total over the 3 axes)
  double robot_sigma_deg = 0.02;
};

/// The robot's chain split at the flange: the holder's pose is before_flange * N * after_flange,
/// where N is the flange's deviation from the model (the robot's repeatability acts there).
struct FlangeChain {
  Rigid before_flange;  // camera <- flange, as the model predicts it
  Rigid after_flange;   // flange <- holder
};
FlangeChain flange_chain(const DeclaredSetup& setup, const EffectParameters& p, const panda::Joints& q);

/// A view's detection noise per axis (its own when set, else the scan's).
inline double centre_sigma(const ScanObservations& o, const ViewObservations& v) {
  return v.centre_sigma_px > 0 ? v.centre_sigma_px : o.centre_sigma_px;
}

/// Where the robot puts the holder under the model (camera frame of the declared source).
Rigid robot_predicted_pose(const DeclaredSetup& setup, const EffectParameters& p, const panda::Joints& q);

/// A pose's deviation N from the model at the flange: rotation vector (rad), then translation
/// (mm), flange coordinates (the robot prior's residual before scaling).
Eigen::Matrix<double, 6, 1> flange_deviation(const DeclaredSetup& setup, const EffectParameters& p, const panda::Joints& q,
                                             const Rigid& T_camera_holder);

/// The chain and detector `scan` declares (it must have a holder).
DeclaredSetup declared_setup(const ScanDescription& scan);

/// The calibrated views of `c` as observations: each ok view's pose, the spheres its fit used and
/// their measured centres, its logged joints (declared joint offsets added); the centre noise
/// from the fits' residuals (per axis, degrees of freedom counted).
ScanObservations observe_calibration(const ScanDescription& scan, const ScanCalibration& c);

/// Radial distortion and intrinsics in the contract's terms.
RadialDistortion distortion_of(const DeclaredSetup& setup, const EffectParameters& p);
Intrinsics intrinsics_of(const DeclaredSetup& setup, const EffectParameters& p);

}  // namespace ctk

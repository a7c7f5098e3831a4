#pragma once
// Closing the loop on a calibrated scan (diagnosis-report.md): which named effect does the
// residual the declared model leaves point to, how large is it, and how much better does the
// model explain the data with it?
//
// Acceptance criterion (the same for every effect): the views are split in two interleaved
// halves; the effect is fitted on one half and judged on the other, where each view's pose is
// refitted with the model fixed and its cost (image chi-square plus robot prior) is compared
// with the cost under the model without the effect. The effect is accepted when the mean
// per-view improvement, in standard errors of those paired differences, passes a threshold that
// holds the scan's false-acceptance rate at `false_acceptance_rate` over every effect of every
// round (round r spends rate / 2^r, shared by its candidates: a Bonferroni bound, Student's t
// quantile), and when the effect's fit on all views does not raise the in-sample cost of the
// model it extends (a model with more freedom that fits worse has not been fitted as a superset).
// Effects are added one at a time, the best first; candidates whose held-out cost is within
// `z_accept` standard errors of the best explain the same residual and are listed in
// `confounded_with`; among them the one earliest in kEffects is reported (robot frames before
// detector parameters: the robot's base is never where the setup says, the detector is measured
// separately). The others stay candidates: one that still explains what the chosen one leaves
// (the two differ at second order and the data are precise enough) is accepted beside it.
// Loads outside the vocabulary (kOutsideEffects: a holder sagging under gravity) compete on the
// same terms; one that explains the residual better than every named effect by more than
// `z_accept` enters the model, is never accepted, and is reported as unexplained structure.
#include <functional>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "ctk/calib/residual_structure.hpp"
#include "ctk/calib/scan_calibration.hpp"
#include "ctk/calib/scan_model_fit.hpp"
#include "ctk/geom/scan.hpp"

namespace ctk {

struct DiagnosisOptions {
  /// Probability that chance alone accepts any effect in a scan that has none (family-wise).
  double false_acceptance_rate = 0.01;
  /// Held-out cost differences within this many standard errors: the data do not tell two
  /// candidates apart (confounding), nor a load outside the vocabulary from a named effect.
  double z_accept = 3.0;
  double robot_sigma_mm = 0.1;  // repeatability the robot prior assumes (3-D RMS)
  double robot_sigma_deg = 0.02;
  int max_effects = 4;
  double min_image_effect_px = 0.01;  // image-only effects must explain at least this much held-out RMS
  /// Of effects the held-out test cannot tell apart, the best-fitting is reported when it leads
  /// the one first in the vocabulary by this many standard errors (paired, held out).
  double best_lead_z = 1.0;
  void validate() const;  // std::invalid_argument naming the field
};

/// How well a model explains the scan: image RMS (px, per sphere), held-out RMS, and how far the
/// robot's prediction is from the best estimate of the actual pose (mm, deg): the per-view pose
/// fitted to image and robot prior together under the final model, the same reference for every
/// figure of a report.
struct ModelError {
  double rms_px = 0, heldout_rms_px = 0;
  double fk_translation_rms_mm = 0, fk_rotation_rms_deg = 0;
};

struct EffectFinding {
  Effect effect;
  bool accepted = false;
  double z = 0;                        // held-out improvement in standard errors
  double threshold_z = 0;              // what z had to pass in its round (false_acceptance_rate spent there)
  bool raised_in_sample_cost = false;  // its fit on all views was worse than the model it extends
  WaldStatistic strength;              // that fit's parameters against none (effect_strength), where judged
  double strength_threshold = 0;       // what strength.chi2 had to pass in its round
  EffectParameters parameters;         // the final model (all views, every accepted effect and load)
  EffectParameters model_before;       // the model it was tested against
  EffectParameters model_after;        // the model right after it entered (its before/after figures)
  Eigen::MatrixXd covariance;          // of this effect's parameters in the final model (may be empty)
  std::vector<Effect> confounded_with;
  ModelError before, after;
};

struct Diagnosis {
  int views_ok = 0;
  double false_acceptance_rate = 0;  // the family-wise rate the acceptance held (DiagnosisOptions)
  // Correlation of the view index with the holder's tilt to gravity: where it is high, a drift in
  // time and a load that follows gravity cannot be told apart (both are then named).
  double time_tilt_correlation = 0;
  ModelError baseline, final_error;
  std::vector<EffectFinding> effects;  // every candidate, accepted ones first in order of acceptance
  EffectParameters model;              // all accepted effects and the loads outside the vocabulary
  std::vector<Effect> accepted;
  std::vector<EffectFinding> outside;  // loads outside the vocabulary (kOutsideEffects) the model includes
  std::vector<StructureFinding> unexplained;
  ScanModelFit before_fit, after_fit;  // all views, for pictures
};

/// The observations behind a calibration (observe_calibration) with the repeatability the options
/// assume, and the detections of spheres the calibration dropped in most views (misplaced ones).
ScanObservations observe_scan(const ScanDescription& scan, const ScanCalibration& calibration, const DiagnosisOptions& options);

Diagnosis diagnose(const ScanObservations& observations, const DiagnosisOptions& options,
                   const std::function<void(const std::string&)>& log = {});

/// Whether sphere_positions was accepted with every sphere free: the holder's geometry as a whole
/// is off (each sphere a little, as a printed holder's are), a case for ctk holder measure.
bool whole_holder_off(const Diagnosis& d);

/// The report in the ctk-diagnosis/1 format.
nlohmann::json diagnosis_to_json(const Diagnosis& d, const ScanObservations& observations);

/// The scan with the accepted effects written into its setup: frames, joint offsets, detector
/// (intrinsics, `radial_distortion`), source drift, sphere list. Calibrating with it starts where
/// the diagnosis ended.
ScanDescription corrected_scan(const ScanDescription& scan, const Diagnosis& d);

}  // namespace ctk

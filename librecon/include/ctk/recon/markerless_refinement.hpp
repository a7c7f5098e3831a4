#pragma once
// Closing the loop without fiducials (circular scans): reconstruct with the current model from
// half of the views, predict the other half, and look for a named effect that predicts them
// better. Each candidate's parameters are fitted on views 1 mod 4 (a parabola through the
// held-out cost at five settings, re-centred until its vertex lies inside) and judged on views
// 3 mod 4. It is accepted when the per-view held-out cost falls by more than `z_accept` standard
// errors of the paired per-view differences, its fit stays inside the physically plausible range
// with a well-curved minimum, and the reconstruction's edges do not blur. Of those, the one that lowers the held-out RMS most
// joins the model and the others are tried again, until none passes. The yardstick is imperfect
// (a coarse FDK from half the views has streaks and blur of its own); the last two rules keep
// candidates that merely compensate it out. Report: ctk-diagnosis/1 (diagnosis-report.md).
#include <functional>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

#include "ctk/recon/detector_pattern.hpp"
#include "ctk/recon/projection_consistency.hpp"

namespace ctk {

struct RefinementOptions {
  double z_accept = 3.0;
  int max_rounds = 4;
  std::vector<std::string> candidates = {"detector_offset", "detector_roll",  "axis_tilt",  "magnification",
                                         "angular_blur",    "beam_hardening", "pixel_gain", "column_gain"};
  double sharpness_tolerance = 0.01;  // an accepted effect may not lower the edge sharpness by more
  double nominal_blur_arc_deg = 0;    // the arc each view is known to integrate (scan log): the blur scan's upper range
  /// Where to begin scanning a parameter (by its reported key, in reported units, e.g. "u0_px")
  /// while the model still holds its nominal value: an estimate from elsewhere (conjugate rays)
  /// saves the scan its walk; the fitted value is still the held-out cost's own minimum.
  std::map<std::string, double> knob_starts;
  void validate() const;  // std::invalid_argument naming the field (or the unknown candidate)
};

// Its implicit moves are noexcept (every member's is); clang-tidy reads a throw into nlohmann::json's.
// NOLINTNEXTLINE(bugprone-exception-escape)
struct RefinedEffect {
  std::string name;
  bool accepted = false;
  int round = 0;
  nlohmann::json parameters, uncertainty;
  /// Per knob: the estimates from the first and second half of the fit views in time, and the
  /// uncertainty that covers both (disjoint_parts.hpp).
  nlohmann::json halves_in_time = nlohmann::json::object();
  double heldout_rms_before = 0, heldout_rms_after = 0, z = 0;
  double sharpness_before = 0, sharpness_after = 0;  // only for accepted effects
  std::vector<std::string> confounded_with;
  std::string note;
};

struct RefinementResult {
  GlobalGeometry geometry;  // accepted effects, relative to the nominal matrices
  ForwardModel model;
  double prediction_smoothing = 0;  // the yardstick's, fitted before any effect
  double heldout_rms_before = 0, heldout_rms_after = 0, sharpness_before = 0, sharpness_after = 0;
  int views = 0;
  std::vector<RefinedEffect> effects;  // every candidate tried, accepted ones in order of acceptance
  /// Parameters or effects asked for that the data cannot fix (a one-row detector sees no
  /// height), with the reason; they are not fitted.
  std::vector<std::pair<std::string, std::string>> not_observable;
  bool structured = false;
  std::string unexplained_note;
  DetectorPattern residual_pattern;    // measured - predicted over the judge views under the final model
  Volume volume_before, volume_after;  // FDK from every view on the fine grid, nominal and refined model
};

/// `coarse` is the grid of the held-out predictions, `fine` that of the sharpness measure.
/// `log` receives one line per step (progress for long runs).
RefinementResult refine_markerless(const ConsistencyProbe& probe, const VolumeLayout& fine, const RefinementOptions& options,
                                   const std::function<void(const std::string&)>& log = {});

nlohmann::json refinement_to_json(const RefinementResult& result);

}  // namespace ctk

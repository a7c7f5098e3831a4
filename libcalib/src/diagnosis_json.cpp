// The diagnosis as the ctk-diagnosis/1 report (../shared/spec/diagnosis-report.md): each effect's
// parameters and uncertainties in the contract's units, the errors before and after.
#include <cmath>

#include "ctk/calib/diagnosis.hpp"
#include "ctk/core/diagnosis_report.hpp"
#include "sphere_offsets.hpp"
#include "time_and_tilt.hpp"

namespace ctk {

namespace {

nlohmann::json vec(const double* p, int n, double scale = 1.0) {
  nlohmann::json a = nlohmann::json::array();
  for (int i = 0; i < n; ++i) a.push_back(p[i] * scale);
  return a;
}

// The contract's parameters and their uncertainties for one effect.
void effect_parameters_json(const EffectFinding& f, const ScanObservations& o, nlohmann::json& parameters,
                            nlohmann::json& uncertainty) {
  const EffectParameters& p = f.parameters;
  const Eigen::MatrixXd& C = f.covariance;
  std::vector<double> sd;
  for (Eigen::Index i = 0; i < C.rows(); ++i) sd.push_back(std::sqrt(std::max(0.0, C(i, i))));
  const double deg = 180.0 / M_PI;
  auto rigid = [&](const double* x) {
    parameters = {{"translation_mm", vec(x + 3, 3)}, {"rotation_deg", vec(x, 3, deg)}};
    if (sd.size() == 6) uncertainty = {{"translation_mm", vec(sd.data() + 3, 3)}, {"rotation_deg", vec(sd.data(), 3, deg)}};
  };
  switch (f.effect) {
    case Effect::robot_base_frame:
      rigid(p.base);
      break;
    case Effect::holder_mount:
      rigid(p.mount);
      break;
    case Effect::joint_offsets:
      parameters = {{"offsets_deg", vec(p.joints, 7, deg)}};
      if (sd.size() == 7) uncertainty = {{"offsets_deg", vec(sd.data(), 7, deg)}};
      break;
    case Effect::source_drift: {
      const double px[2] = {p.drift[0] / o.setup.detector.pitch_u_mm, p.drift[1] / o.setup.detector.pitch_v_mm};
      parameters = {{"drift_px_per_100_views", vec(px, 2)}, {"drift_mm_per_100_views", vec(p.drift, 2)}};
      if (sd.size() == 2)
        uncertainty = {{"drift_px_per_100_views", {sd[0] / o.setup.detector.pitch_u_mm, sd[1] / o.setup.detector.pitch_v_mm}}};
      break;
    }
    case Effect::detector_intrinsics: {
      const Intrinsics K = intrinsics_of(o.setup, p);
      parameters = {{"fu_px", K.fu_px}, {"fv_px", K.fv_px}, {"skew_px", K.skew_px},
                    {"u0_px", K.u0_px}, {"v0_px", K.v0_px}, {"source_to_detector_mm", K.fu_px * o.setup.detector.pitch_u_mm}};
      if (sd.size() == 3) uncertainty = {{"u0_px", sd[0]}, {"v0_px", sd[1]}, {"fu_px", sd[2]}};
      break;
    }
    case Effect::detector_distortion: {
      const RadialDistortion r = distortion_of(o.setup, p);
      parameters = {{"k1_per_px2", r.k1_per_px2}, {"center_px", {r.centre_px.x(), r.centre_px.y()}}};
      if (sd.size() == 3) uncertainty = {{"k1_per_px2", sd[0] / (360.0 * 360.0 * 360.0)}, {"center_px", {sd[1], sd[2]}}};
      break;
    }
    case Effect::sphere_positions: {
      // Only the spheres whose offset is significant (chi-square, 3 dof, p < 0.001 each).
      nlohmann::json spheres = nlohmann::json::array(), sigmas = nlohmann::json::array();
      for (std::size_t k = 0; k < p.spheres.size(); ++k) {
        const Eigen::Vector3d& x = p.spheres[k];
        Eigen::Vector3d s(0, 0, 0);
        const bool significant = sphere_offset_significant(x, C, k, &s);
        if (!significant) continue;
        spheres.push_back({{"index", k}, {"offset_mm", {x.x(), x.y(), x.z()}}});
        sigmas.push_back({{"index", k}, {"offset_mm", {s.x(), s.y(), s.z()}}});
      }
      parameters = {{"spheres", spheres}};
      uncertainty = {{"spheres", sigmas}};
      // Fitted with every sphere free: the holder's geometry as a whole is off (a printed holder),
      // which one scan of it measures sphere by sphere (ctk holder measure).
      if (f.accepted && all_spheres_free(f.parameters)) {
        parameters["whole_holder"] = true;
        parameters["next"] =
            "measure the holder once from a scan of 60 or more well-spread views (ctk holder measure) and declare the holder "
            "file it writes";
      }
      break;
    }
    case Effect::gravity_load:
      break;  // reported in `unexplained`, not among the effects
  }
}

void error_json(nlohmann::json& j, const ModelError& before, const ModelError& after, bool robot) {
  j["rms_px_before"] = before.rms_px;
  j["rms_px_after"] = after.rms_px;
  j["heldout_rms_px_before"] = before.heldout_rms_px;
  j["heldout_rms_px_after"] = after.heldout_rms_px;
  if (robot) {
    j["fk_translation_rms_mm_before"] = before.fk_translation_rms_mm;
    j["fk_translation_rms_mm_after"] = after.fk_translation_rms_mm;
    j["fk_rotation_rms_deg_before"] = before.fk_rotation_rms_deg;
    j["fk_rotation_rms_deg_after"] = after.fk_rotation_rms_deg;
  }
}

}  // namespace

nlohmann::json diagnosis_to_json(const Diagnosis& d, const ScanObservations& o) {
  DiagnosisReport report;
  report.baseline = {{"rms_px", d.baseline.rms_px}, {"heldout_rms_px", d.baseline.heldout_rms_px}, {"views_ok", d.views_ok}};
  if (o.setup.robot) {
    report.baseline["fk_translation_rms_mm"] = d.baseline.fk_translation_rms_mm;
    report.baseline["fk_rotation_rms_deg"] = d.baseline.fk_rotation_rms_deg;
  }
  for (const EffectFinding& f : d.effects) {
    ReportedEffect e;
    e.name = effect_name(f.effect);
    e.accepted = f.accepted;
    e.heldout_improvement_z = f.z;
    if (f.accepted) effect_parameters_json(f, o, e.parameters, e.uncertainty);
    for (Effect c : f.confounded_with) e.confounded_with.push_back(effect_name(c));
    e.figures = {{"threshold_z", f.threshold_z}, {"raises_in_sample_cost", f.raised_in_sample_cost}};
    if (f.strength.dof > 0)
      e.figures["strength"] = {{"chi2", f.strength.chi2}, {"dof", f.strength.dof}, {"threshold_chi2", f.strength_threshold}};
    error_json(e.figures, f.before, f.after, o.setup.robot);
    report.effects.push_back(std::move(e));
  }
  for (const auto& s : d.unexplained)
    report.unexplained_note += (report.unexplained_note.empty() ? "" : " | ") + s.where + ": " + s.what;
  if (report.unexplained_note.empty())
    report.unexplained_note = "residuals consistent with detection noise and robot repeatability";
  report.structured = !d.unexplained.empty();
  report.final_error = {{"rms_px", d.final_error.rms_px}, {"heldout_rms_px", d.final_error.heldout_rms_px}};
  if (o.setup.robot) {
    report.final_error["fk_translation_rms_mm"] = d.final_error.fk_translation_rms_mm;
    report.final_error["fk_rotation_rms_deg"] = d.final_error.fk_rotation_rms_deg;
  }
  report.criterion =
      "an effect is accepted when, fitted on one half of the views (interleaved) and judged on the other, the mean per-view "
      "improvement of the held-out cost passes threshold_z standard errors (Student's t; round r of the greedy search "
      "spends false_acceptance_rate / 2^r, shared by its candidates, so chance accepts anything in a scan with probability "
      "at most false_acceptance_rate), its fit on all views does not raise the in-sample cost of the model it extends, and in "
      "that fit its parameters stand from none by more than strength.threshold_chi2 (a Wald chi-square at the round's level)";
  report.extra = {
      {"noise",
       {{"centre_sigma_px", o.centre_sigma_px}, {"robot_sigma_mm", o.robot_sigma_mm}, {"robot_sigma_deg", o.robot_sigma_deg}}},
      {"false_acceptance_rate", d.false_acceptance_rate},
      {"time_and_tilt",
       {{"correlation", d.time_tilt_correlation}, {"confounded", TimeAndTilt{d.time_tilt_correlation}.confounded()}}}};
  return report.to_json();
}

}  // namespace ctk

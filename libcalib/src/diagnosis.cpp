#include "ctk/calib/diagnosis.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <map>
#include <numeric>
#include <sstream>

#include "ctk/core/diagnosis_report.hpp"
#include "ctk/core/error.hpp"
#include "ctk/core/statistics.hpp"
#include "ctk/geom/panda.hpp"
#include "time_and_tilt.hpp"

namespace ctk {

namespace {

bool all_spheres_free(const EffectParameters& p) {
  return !p.free_spheres.empty() && std::find(p.free_spheres.begin(), p.free_spheres.end(), false) == p.free_spheres.end();
}

constexpr double kDegree = M_PI / 180.0;

std::vector<std::size_t> all_views(const ScanObservations& o) {
  std::vector<std::size_t> v(o.views.size());
  std::iota(v.begin(), v.end(), std::size_t{0});
  return v;
}

// Held out: each half fitted on the other, every held-out view's pose refitted with the model
// fixed. Returns per-view costs (all views, in order) and the held-out image RMS.
struct HeldOut {
  std::vector<double> cost;
  double rms_px = 0;
};

HeldOut held_out(const ScanObservations& o, const std::vector<Effect>& active, const EffectParameters& start) {
  HeldOut h;
  h.cost.assign(o.views.size(), 0.0);
  double sq = 0;
  int n = 0;
  for (int fold = 0; fold < 2; ++fold) {
    std::vector<std::size_t> train, test;
    for (std::size_t i = 0; i < o.views.size(); ++i) (static_cast<int>(i % 2) == fold ? test : train).push_back(i);
    const EffectParameters model = active.empty() ? start : fit_scan_model(o, active, train, start).parameters;
    const ScanModelFit f = fit_view_poses(o, model, test);
    for (std::size_t k = 0; k < test.size(); ++k) {
      h.cost[test[k]] = f.cost[k];
      sq += f.image_sq_px[k];
      n += f.residual_count[k] / 2;
    }
  }
  h.rms_px = n > 0 ? std::sqrt(sq / n) : 0.0;
  return h;
}

// Whether sphere k's offset x differs from zero beyond chance (chi-square, 3 dof, p < 0.001),
// from the covariance C of all sphere offsets (pseudo-inverse: the gauge leaves directions
// unfixed); without a covariance, beyond 0.03 mm. `sigma` gets its standard deviations.
bool sphere_offset_significant(const Eigen::Vector3d& x, const Eigen::MatrixXd& C, std::size_t k, Eigen::Vector3d* sigma) {
  if (C.rows() < static_cast<Eigen::Index>(3 * (k + 1))) return x.norm() > 0.03;
  const Eigen::Matrix3d Ck = C.block(static_cast<Eigen::Index>(3 * k), static_cast<Eigen::Index>(3 * k), 3, 3);
  if (sigma) *sigma = Ck.diagonal().cwiseMax(0.0).cwiseSqrt();
  const Eigen::Matrix3d inv = Ck.completeOrthogonalDecomposition().pseudoInverse();
  return x.dot(inv * x) > 16.27;
}

// Which spheres are misplaced: fitted all together (gauge fixed), a misplaced sphere stands out
// from the rest, while an error of the detector or the robot that the offsets absorb spreads over
// many of them. Offsets beyond 6 robust deviations of the median (and 0.03 mm) are free in the
// model; empty when none stands out.
std::vector<bool> misplaced_spheres(const ScanObservations& o, const std::vector<Effect>& active, EffectParameters start) {
  start.free_spheres.clear();
  std::vector<std::size_t> views(o.views.size());
  std::iota(views.begin(), views.end(), std::size_t{0});
  const ScanModelFit all = fit_scan_model(o, active, views, start, true);
  // The sphere offsets' block of the covariance (they come last among the active effects).
  const auto slot = static_cast<std::size_t>(std::find(active.begin(), active.end(), Effect::sphere_positions) - active.begin());
  Eigen::MatrixXd C;
  if (all.covariance.size() > 0) {
    const auto n = static_cast<Eigen::Index>(3 * all.parameters.spheres.size());
    C = all.covariance.block(all.covariance_offsets[slot], all.covariance_offsets[slot], n, n);
  }
  std::vector<double> m;
  for (const auto& x : all.parameters.spheres) m.push_back(x.norm());
  std::vector<double> deviation = m;
  const double centre = median_in_place(deviation);
  for (double& x : deviation) x = std::abs(x - centre);
  const double limit = std::max(0.03, centre + 6 * 1.4826 * median_in_place(deviation));
  // A sphere's 3-D place is only fixed by views from well-separated directions: one seen in a
  // few views, or from a narrow cone of directions, fits any bias of its centres (a sample's edge
  // over it) with a large, meaningless offset.
  std::vector<std::vector<Eigen::Vector3d>> seen_from(m.size());
  for (const auto& view : o.views)
    for (int k : view.spheres) seen_from[static_cast<std::size_t>(k)].push_back(view.T_calibrated.linear().row(2).transpose());
  auto well_observed = [&](std::size_t k) {
    const auto& d = seen_from[k];
    if (d.size() < 10) return false;
    double widest = 0;
    for (std::size_t i = 0; i < d.size(); ++i)
      for (std::size_t j = i + 1; j < d.size(); ++j) widest = std::max(widest, std::acos(std::clamp(d[i].dot(d[j]), -1.0, 1.0)));
    return widest > 30 * kDegree;
  };
  std::vector<bool> free(m.size(), false);
  bool any = false;
  for (std::size_t k = 0; k < m.size(); ++k)
    any |= free[k] = m[k] > limit && well_observed(k) && sphere_offset_significant(all.parameters.spheres[k], C, k, nullptr);
  return any ? free : std::vector<bool>{};
}

// The robot's prediction under `model` against reference poses: the best estimate of where the
// holder was (image and robot repeatability combined under the final model). An image-only pose
// would add its own depth noise (~0.15 mm per view at the reference setup) to every figure.
void fk_error(const ScanObservations& o, const std::vector<Rigid>& reference, const EffectParameters& model, ModelError& e) {
  if (!o.setup.robot) return;
  double t2 = 0, r2 = 0;
  int n = 0;
  for (std::size_t i = 0; i < o.views.size(); ++i) {
    if (!o.views[i].joints) continue;
    const Rigid predicted = robot_predicted_pose(o.setup, model, *o.views[i].joints);
    t2 += (reference[i].translation() - predicted.translation()).squaredNorm();
    const double angle = rotation_angle_deg(reference[i].linear() * predicted.linear().transpose());
    r2 += angle * angle;
    ++n;
  }
  if (n == 0) return;
  e.fk_translation_rms_mm = std::sqrt(t2 / n);
  e.fk_rotation_rms_deg = std::sqrt(r2 / n);
}

// The image figures; the robot figures are filled in once the final model gives the reference.
ModelError image_error(const ScanModelFit& all, const HeldOut& h) {
  ModelError e;
  e.rms_px = all.image_rms_px();
  e.heldout_rms_px = h.rms_px;
  return e;
}

// The gravity load (kOutsideEffects' one member), in the report's words.
StructureFinding gravity_load_finding(const EffectFinding& f, const TimeAndTilt& time_tilt) {
  auto sd = [&](int i) { return f.covariance.rows() > i ? std::sqrt(std::max(0.0, f.covariance(i, i))) : 0.0; };
  std::ostringstream what;
  what << "a load that follows gravity explains the residual better than any listed effect (held-out improvement " << f.z
       << " standard errors): with its axis horizontal the holder turns " << f.parameters.gravity[0] / kDegree << " +- "
       << sd(0) / kDegree << " deg (about the axis x gravity) and shifts " << f.parameters.gravity[1] << " +- " << sd(1)
       << " mm (across its axis), less as it tilts towards the vertical, as a holder sagging under its weight does; "
       << "the held-out RMS goes from " << f.before.heldout_rms_px << " to " << f.after.heldout_rms_px << " px";
  if (time_tilt.confounded())
    what << "; on this trajectory the tilt changes with time (correlation " << time_tilt.correlation
         << " with the view index): a drift in time (source_drift) would look alike";
  return {"by gravity", what.str()};
}

}  // namespace

void DiagnosisOptions::validate() const {
  require_option(false_acceptance_rate > 0 && false_acceptance_rate < 1, "DiagnosisOptions.false_acceptance_rate",
                 "a probability between 0 and 1 (exclusive)", false_acceptance_rate);
  require_option(z_accept > 0, "DiagnosisOptions.z_accept", "a number above 0 (standard errors)", z_accept);
  require_option(robot_sigma_mm > 0, "DiagnosisOptions.robot_sigma_mm", "a number above 0", robot_sigma_mm);
  require_option(robot_sigma_deg > 0, "DiagnosisOptions.robot_sigma_deg", "a number above 0", robot_sigma_deg);
  require_option(max_effects >= 1, "DiagnosisOptions.max_effects", "at least 1", max_effects);
  require_option(min_image_effect_px >= 0, "DiagnosisOptions.min_image_effect_px", "a number of 0 or more", min_image_effect_px);
  require_option(best_lead_z >= 0, "DiagnosisOptions.best_lead_z", "a number of 0 or more (standard errors)", best_lead_z);
}

ScanObservations observe_scan(const ScanDescription& scan, const ScanCalibration& c, const DiagnosisOptions& options) {
  options.validate();
  ScanObservations o = observe_calibration(scan, c);
  o.robot_sigma_mm = options.robot_sigma_mm;
  o.robot_sigma_deg = options.robot_sigma_deg;
  // A sphere the calibration left out as an outlier in most of the views that matched it is off
  // in every view: a property of the sphere (misplaced), not of one view's background. Its
  // detections go back into the observations, so the diagnosis can find where it really is.
  std::map<int, int> used, dropped;
  for (const ViewCalibration& r : c.views) {
    if (r.status != ViewStatus::ok) continue;
    for (int k : r.spheres) ++used[k];
    for (int k : r.outlier_spheres) ++dropped[k];
  }
  auto consistently_off = [&](int k) { return dropped[k] >= 5 && dropped[k] > used[k]; };
  for (ViewObservations& view : o.views) {
    const ViewCalibration& r = c.views[static_cast<std::size_t>(view.view)];
    for (std::size_t k = 0; k < r.outlier_spheres.size(); ++k)
      if (consistently_off(r.outlier_spheres[k])) {
        view.spheres.push_back(r.outlier_spheres[k]);
        view.measured_px.push_back(r.outlier_detected_px[k]);
      }
  }
  return o;
}

Diagnosis diagnose(const ScanObservations& o, const DiagnosisOptions& options,
                   const std::function<void(const std::string&)>& log) {
  options.validate();
  Diagnosis d;
  d.views_ok = static_cast<int>(o.views.size());
  d.false_acceptance_rate = options.false_acceptance_rate;
  auto say = [&](const std::string& s) {
    if (log) log(s);
  };
  const TimeAndTilt time_tilt = o.setup.robot ? time_and_tilt(o) : TimeAndTilt{};
  d.time_tilt_correlation = time_tilt.correlation;
  std::vector<Effect> candidates, outside;
  for (Effect e : kEffects)
    if (o.setup.robot || !needs_robot(e)) candidates.push_back(e);
  for (Effect e : kOutsideEffects)
    if (o.setup.robot || !needs_robot(e)) outside.push_back(e);
  std::vector<Effect> modelled;  // the accepted effects and the loads found outside the vocabulary

  EffectParameters current;
  current.spheres.assign(o.setup.holder.spheres_mm.size(), Eigen::Vector3d::Zero());
  HeldOut current_held = held_out(o, {}, current);
  ScanModelFit current_fit = fit_view_poses(o, current, all_views(o));
  d.before_fit = current_fit;
  d.baseline = image_error(current_fit, current_held);
  say("baseline: " + std::to_string(d.baseline.rms_px) + " px RMS, held out " + std::to_string(d.baseline.heldout_rms_px));

  // Fits `chosen` into the model on every view (its value and covariance are read from the final
  // model once the loop ends).
  auto add_to_model = [&](Effect chosen, const HeldOut& held, EffectFinding& f) {
    modelled.push_back(chosen);
    current_fit = fit_scan_model(o, modelled, all_views(o), current, true);
    current = current_fit.parameters;
    current_held = held;
    f.model_after = current;
    f.after = image_error(current_fit, current_held);
    d.final_error = f.after;
  };

  std::vector<EffectFinding> rejected_last;
  int round = 0;
  while (static_cast<int>(d.accepted.size()) < options.max_effects && !candidates.empty()) {
    ++round;
    struct Trial {
      Effect effect;
      HeldOut held;
      double z;
      std::vector<bool> free_spheres;  // sphere_positions: the spheres its fit frees
      bool in_vocabulary = true;
    };
    std::vector<Trial> trials;
    for (Effect e : candidates) {
      std::vector<Effect> active = modelled;
      active.push_back(e);
      EffectParameters start = current;
      if (e == Effect::sphere_positions) {
        // Only spheres that stand out are candidates; with none, the effect has nothing to name
        // (offsets spread over all spheres absorb other errors and noise instead).
        start.free_spheres = misplaced_spheres(o, active, current);
        if (start.free_spheres.empty()) {
          // None stands out: every sphere a little off (a printed holder) is the holder's geometry
          // as a whole, tried with every centre free under the gauge.
          start.free_spheres.assign(o.setup.holder.spheres_mm.size(), true);
          say("  sphere_positions: no sphere stands out from the others; every sphere tried (the holder as a whole)");
        } else {
          std::string which;
          for (std::size_t k = 0; k < start.free_spheres.size(); ++k)
            if (start.free_spheres[k]) which += " " + std::to_string(k);
          say("  sphere_positions: spheres standing out:" + which);
        }
      }
      Trial t{e, held_out(o, active, start), 0, start.free_spheres};
      t.z = paired_z(current_held.cost, t.held.cost);
      say(std::string("  ") + effect_name(e) + ": held-out improvement " + std::to_string(t.z) + " standard errors");
      trials.push_back(std::move(t));
    }
    for (Effect e : outside) {
      std::vector<Effect> active = modelled;
      active.push_back(e);
      Trial t{e, held_out(o, active, current), 0, {}, false};
      t.z = paired_z(current_held.cost, t.held.cost);
      say(std::string("  ") + effect_name(e) + " (outside the vocabulary): held-out improvement " + std::to_string(t.z) +
          " standard errors");
      trials.push_back(std::move(t));
    }
    // The best held-out cost among those that pass; the equivalents of the best are confounded.
    auto total = [](const Trial& t) { return std::accumulate(t.held.cost.begin(), t.held.cost.end(), 0.0); };
    // An effect must also lower the held-out chi-square by more than its parameter count (what
    // fitting noise alone buys on the training half): a direction the data leave nearly free (a
    // joint offset beside the base frame it repeats) can shift every held-out view the same
    // negligible way and so pass the paired test with nothing to explain.
    const double current_total = std::accumulate(current_held.cost.begin(), current_held.cost.end(), 0.0);
    auto free_parameters = [&](const Trial& t) {
      if (t.effect != Effect::sphere_positions) return parameter_count(t.effect, o);
      return 3 * static_cast<int>(std::count(t.free_spheres.begin(), t.free_spheres.end(), true));
    };
    // The scan's false-acceptance rate, spent over the rounds (round r: rate / 2^r, the sum below
    // the rate however many rounds run) and shared by the round's trials (Bonferroni): chance
    // passes any trial of any round with probability at most the rate.
    const double level =
        options.false_acceptance_rate / std::ldexp(1.0, std::min(round, 60)) / static_cast<double>(trials.size());
    const double threshold = one_sided_threshold(level, std::max<std::size_t>(o.views.size(), 2));
    say("  round " + std::to_string(round) + ": an effect must pass " + std::to_string(threshold) + " standard errors");
    auto passes_held_out = [&](const Trial& t) {
      if (!(t.z > threshold)) return false;
      if (!(current_total - total(t) > free_parameters(t))) return false;
      // Effects seen only in the image must also explain more than the detector's own systematic
      // floor (centres are biased by ~0.02 px RMS even without noise): a longer scan makes such a
      // bias "significant" without making it a physical effect.
      if (t.effect != Effect::detector_distortion && t.effect != Effect::sphere_positions) return true;
      const double explained2 = current_held.rms_px * current_held.rms_px - t.held.rms_px * t.held.rms_px;
      return explained2 > options.min_image_effect_px * options.min_image_effect_px;
    };
    // Nested models: with the effect's freedom added, the fit on all views must do at least as well
    // as the model without it, in its whole cost and in the images alone (fitted once per trial
    // that passes the rest, then remembered). A missing effect leaves the images misfitted: adding
    // it lets the robot-tied poses go where the images put them. An effect that lowers the robot
    // prior's share while the images fit worse only moves the poses away from the images: on the
    // README's example (a base offset only, a sample in the beam) a holder mount did that
    // (0.102682 -> 0.102763 px) and passed the held-out test at 4.95 standard errors, because
    // interleaved halves share whatever smooth detection bias the sample gives the spheres.
    const double current_cost = std::accumulate(current_fit.cost.begin(), current_fit.cost.end(), 0.0);
    const double current_image = std::accumulate(current_fit.image_sq_px.begin(), current_fit.image_sq_px.end(), 0.0);
    std::map<Effect, bool> raises_in_sample;
    auto raises_cost = [&](const Trial& t) {
      if (const auto it = raises_in_sample.find(t.effect); it != raises_in_sample.end()) return it->second;
      std::vector<Effect> active = modelled;
      active.push_back(t.effect);
      EffectParameters start = current;
      if (t.effect == Effect::sphere_positions) start.free_spheres = t.free_spheres;
      const ScanModelFit fit = fit_scan_model(o, active, all_views(o), start);
      const double cost = std::accumulate(fit.cost.begin(), fit.cost.end(), 0.0);
      const double image = std::accumulate(fit.image_sq_px.begin(), fit.image_sq_px.end(), 0.0);
      auto above = [](double after, double before) { return after > before + 1e-6 * std::max(1.0, before); };
      const bool raised = above(cost, current_cost) || above(image, current_image);
      if (raised)
        say(std::string("  ") + effect_name(t.effect) + ": its fit on all views raises the in-sample cost (" +
            std::to_string(current_cost) + " -> " + std::to_string(cost) + ") or the image misfit (" +
            std::to_string(current_image) + " -> " + std::to_string(image) + " px^2): not a superset of the model");
      return raises_in_sample[t.effect] = raised;
    };
    auto passes = [&](const Trial& t) { return passes_held_out(t) && !raises_cost(t); };
    const Trial *best = nullptr, *load = nullptr;
    for (const Trial& t : trials) {
      const Trial*& slot = t.in_vocabulary ? best : load;
      if (passes(t) && (!slot || total(t) < total(*slot))) slot = &t;
    }
    // A load outside the vocabulary enters the model only where it explains the residual better
    // than every named effect (by the same held-out test): a holder sagging on a cap of directions
    // is then found as a load, not as a base offset that takes its mean; where the two explain the
    // data equally well, the named effect is reported.
    if (load && (!best || paired_z(best->held.cost, load->held.cost) > options.z_accept)) {
      EffectFinding f;
      f.effect = load->effect;
      f.z = load->z;
      f.threshold_z = threshold;
      f.before = d.accepted.empty() && d.outside.empty() ? d.baseline : d.final_error;
      f.model_before = current;
      add_to_model(load->effect, load->held, f);
      say(std::string("found outside the vocabulary: ") + effect_name(load->effect) + ": " + std::to_string(f.before.rms_px) +
          " -> " + std::to_string(f.after.rms_px) + " px");
      outside.erase(std::remove(outside.begin(), outside.end(), f.effect), outside.end());
      d.outside.push_back(std::move(f));
      continue;
    }
    if (!best) {
      for (const Trial& t : trials) {
        if (!t.in_vocabulary) continue;
        EffectFinding f;
        f.effect = t.effect;
        f.z = t.z;
        f.threshold_z = threshold;
        const auto judged = raises_in_sample.find(t.effect);
        f.raised_in_sample_cost = judged != raises_in_sample.end() && judged->second;
        f.before = d.effects.empty() && d.outside.empty() ? d.baseline : d.final_error;
        f.before.heldout_rms_px = current_held.rms_px;
        f.after = f.before;
        f.after.heldout_rms_px = t.held.rms_px;
        f.model_before = current;
        rejected_last.push_back(f);
      }
      break;
    }
    std::vector<Effect> equivalent;
    for (const Trial& t : trials)
      if (t.in_vocabulary && passes(t) && paired_z(t.held.cost, best->held.cost) < options.z_accept)
        equivalent.push_back(t.effect);
    // Among effects the held-out test cannot tell apart, the vocabulary's order names the one
    // reported (the frames before the detector), unless the best-fitting one leads it by
    // `best_lead_z`: then the data prefer it (a drift that grows with the view index fits better
    // than the constant offset that takes its mean) and the other is named as confounded.
    const auto trial_of = [&](Effect e) -> const Trial& {
      return *std::find_if(trials.begin(), trials.end(), [&](const Trial& x) { return x.effect == e; });
    };
    Effect chosen = *std::min_element(equivalent.begin(), equivalent.end(), [](Effect a, Effect b) {
      return std::find(kEffects.begin(), kEffects.end(), a) < std::find(kEffects.begin(), kEffects.end(), b);
    });
    if (chosen != best->effect && paired_z(trial_of(chosen).held.cost, best->held.cost) >= options.best_lead_z)
      chosen = best->effect;
    const Trial& t = trial_of(chosen);

    EffectFinding f;
    f.effect = chosen;
    f.accepted = true;
    f.z = t.z;
    f.threshold_z = threshold;
    for (Effect e : equivalent)
      if (e != chosen) f.confounded_with.push_back(e);
    // A drift in time on a trajectory whose tilt changes with time is as much a load that follows
    // gravity: named beside it, not chosen between (time_and_tilt.hpp).
    if (chosen == Effect::source_drift && time_tilt.confounded()) {
      f.confounded_with.push_back(Effect::gravity_load);
      say("  source_drift: the holder's tilt changes with time on this trajectory (correlation " +
          std::to_string(time_tilt.correlation) + "): a load that follows gravity would look alike");
    }
    f.before = d.accepted.empty() && d.outside.empty() ? d.baseline : d.final_error;
    f.model_before = current;
    d.accepted.push_back(chosen);
    if (chosen == Effect::sphere_positions) current.free_spheres = t.free_spheres;  // as judged
    add_to_model(chosen, t.held, f);
    say(std::string("accepted ") + effect_name(chosen) + ": " + std::to_string(f.before.rms_px) + " -> " +
        std::to_string(f.after.rms_px) + " px");
    d.effects.push_back(f);
    // The accepted effect leaves the candidates; those it was confounded with stay: where the data
    // are precise enough to tell them apart (a principal-point shift is a rotation about the focal
    // spot to first order only), the one the preference passed over may still explain what the
    // chosen one leaves, and it is then accepted beside it on the same held-out terms.
    candidates.erase(std::remove(candidates.begin(), candidates.end(), chosen), candidates.end());
  }
  if (modelled.empty()) d.final_error = d.baseline;
  for (auto& f : rejected_last) d.effects.push_back(f);
  d.model = current;
  d.after_fit = modelled.empty() ? d.before_fit : current_fit;
  // The robot channel's figures, all against the same reference poses.
  const std::vector<Rigid>& reference = d.after_fit.poses;
  fk_error(o, reference, EffectParameters{}, d.baseline);
  fk_error(o, reference, d.model, d.final_error);
  for (EffectFinding& f : d.effects) {
    fk_error(o, reference, f.model_before, f.before);
    fk_error(o, reference, f.accepted ? f.model_after : f.model_before, f.after);
  }
  for (EffectFinding& f : d.outside) {
    fk_error(o, reference, f.model_before, f.before);
    fk_error(o, reference, f.model_after, f.after);
  }
  // What is reported of each effect is its value in the final model, fitted with all the others
  // (a later one, a load above all, can take up part of what an earlier one first absorbed).
  auto in_final_model = [&](EffectFinding& f) {
    const auto slot = static_cast<std::size_t>(std::find(modelled.begin(), modelled.end(), f.effect) - modelled.begin());
    f.parameters = current;
    if (current_fit.covariance.size() > 0) {
      const int start = current_fit.covariance_offsets[slot], size = parameter_count(f.effect, o);
      f.covariance = current_fit.covariance.block(start, start, size, size);
    }
  };
  for (EffectFinding& f : d.effects)
    if (f.accepted) in_final_model(f);
  for (EffectFinding& f : d.outside) in_final_model(f);
  // A load found outside the vocabulary is structure the contract's effects do not explain.
  for (const EffectFinding& f : d.outside) d.unexplained.push_back(gravity_load_finding(f, time_tilt));
  for (StructureFinding& s : find_structure(o, d.after_fit)) d.unexplained.push_back(std::move(s));
  return d;
}

}  // namespace ctk

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
  const double deg = 1.0 / kDegree;
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

bool whole_holder_off(const Diagnosis& d) {
  return std::find(d.accepted.begin(), d.accepted.end(), Effect::sphere_positions) != d.accepted.end() &&
         all_spheres_free(d.model);
}

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
      "at most false_acceptance_rate) and its fit on all views does not raise the in-sample cost of the model it extends";
  report.extra = {
      {"noise",
       {{"centre_sigma_px", o.centre_sigma_px}, {"robot_sigma_mm", o.robot_sigma_mm}, {"robot_sigma_deg", o.robot_sigma_deg}}},
      {"false_acceptance_rate", d.false_acceptance_rate},
      {"time_and_tilt",
       {{"correlation", d.time_tilt_correlation}, {"confounded", TimeAndTilt{d.time_tilt_correlation}.confounded()}}}};
  return report.to_json();
}

ScanDescription corrected_scan(const ScanDescription& scan, const Diagnosis& d) {
  ScanDescription out = scan;
  const EffectParameters& p = d.model;
  auto offset = [](const double* x) {
    return make_rigid(rotation_from_vector(Eigen::Vector3d(x[0], x[1], x[2])), Eigen::Vector3d(x[3], x[4], x[5]));
  };
  for (Effect e : d.accepted) {
    switch (e) {
      case Effect::robot_base_frame:
        out.panda->T_camera_base = scan.panda->T_camera_base * offset(p.base);
        break;
      case Effect::holder_mount:
        out.panda->T_flange_holder = offset(p.mount) * scan.panda->T_flange_holder;
        break;
      case Effect::joint_offsets:
        for (int j = 0; j < panda::kJointCount; ++j) out.panda->joint_offsets_rad[static_cast<std::size_t>(j)] += p.joints[j];
        break;
      case Effect::sphere_positions:
        for (std::size_t k = 0; k < out.holder->spheres_mm.size(); ++k) out.holder->spheres_mm[k] += p.spheres[k];
        break;
      case Effect::detector_intrinsics:
        out.principal_point_px += Eigen::Vector2d(p.intrinsics[0], p.intrinsics[1]);
        out.source_to_detector_mm *= 1.0 + p.intrinsics[2] / scan.intrinsics().fu_px;
        break;
      case Effect::detector_distortion: {
        // The centre is absolute (the declared principal point plus the fitted offset). Found on
        // top of a declared distortion, the k1 add up (the centres are taken as the same).
        const RadialDistortion found = distortion_of(declared_setup(scan), p);
        if (out.distortion)
          out.distortion->k1_per_px2 += found.k1_per_px2;
        else
          out.distortion = found;
        break;
      }
      case Effect::source_drift:
        out.source_drift_mm_per_100_views += Eigen::Vector2d(p.drift[0], p.drift[1]);
        break;
      case Effect::gravity_load:
        break;  // never accepted: the scan format has no place for it
    }
  }
  return out;
}

}  // namespace ctk

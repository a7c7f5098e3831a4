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
#include "sphere_offsets.hpp"
#include "time_and_tilt.hpp"

namespace ctk {

namespace {

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

// The greedy search diagnose() runs: round by round every candidate effect, and every load outside
// the vocabulary, is fitted on one half of the views and judged on the other; the one that passes
// with the best held-out fit enters the model (or, among those the test cannot tell apart, the
// vocabulary's first), until none passes.
class EffectSearch {
 public:
  EffectSearch(const ScanObservations& o, const DiagnosisOptions& options, const std::function<void(const std::string&)>& log)
      : o_(o), options_(options), log_(log), time_tilt_(o.setup.robot ? time_and_tilt(o) : TimeAndTilt{}) {
    d_.views_ok = static_cast<int>(o.views.size());
    d_.false_acceptance_rate = options.false_acceptance_rate;
    d_.time_tilt_correlation = time_tilt_.correlation;
    for (Effect e : kEffects)
      if (o.setup.robot || !needs_robot(e)) candidates_.push_back(e);
    for (Effect e : kOutsideEffects)
      if (o.setup.robot || !needs_robot(e)) outside_.push_back(e);
    current_.spheres.assign(o.setup.holder.spheres_mm.size(), Eigen::Vector3d::Zero());
    current_held_ = held_out(o, {}, current_);
    current_fit_ = fit_view_poses(o, current_, all_views(o));
    d_.before_fit = current_fit_;
    d_.baseline = image_error(current_fit_, current_held_);
    say("baseline: " + std::to_string(d_.baseline.rms_px) + " px RMS, held out " + std::to_string(d_.baseline.heldout_rms_px));
  }

  bool may_add_an_effect() const { return static_cast<int>(d_.accepted.size()) < options_.max_effects && !candidates_.empty(); }

  // One round: every trial judged against this round's threshold; a load outside the vocabulary or
  // a named effect enters the model. False when none passed (the search ends).
  bool round() {
    ++round_;
    const std::vector<Trial> trials = this_rounds_trials();
    threshold_ = round_threshold(trials.size());
    say("  round " + std::to_string(round_) + ": an effect must pass " + std::to_string(threshold_) + " standard errors");
    current_held_total_ = sum(current_held_.cost);
    current_cost_ = sum(current_fit_.cost);
    current_image_ = sum(current_fit_.image_sq_px);
    in_sample_.clear();
    const Trial *best = nullptr, *load = nullptr;
    for (const Trial& t : trials) {
      const Trial*& slot = t.in_vocabulary ? best : load;
      if (passes(t) && (!slot || sum(t.held.cost) < sum(slot->held.cost))) slot = &t;
    }
    // A load outside the vocabulary enters the model only where it explains the residual better
    // than every named effect (by the same held-out test): a holder sagging on a cap of directions
    // is then found as a load, not as a base offset that takes its mean; where the two explain the
    // data equally well, the named effect is reported.
    if (load && (!best || paired_z(best->held.cost, load->held.cost) > options_.z_accept)) {
      add_load(*load);
      return true;
    }
    if (!best) {
      record_the_last_rounds_rejections(trials);
      return false;
    }
    accept(trials, *best);
    return true;
  }

  // The diagnosis: the robot channel's figures, each effect's value in the final model, and the
  // structure no effect explains.
  Diagnosis result() && {
    if (modelled_.empty()) d_.final_error = d_.baseline;
    for (auto& f : rejected_last_) d_.effects.push_back(f);
    d_.model = current_;
    d_.after_fit = modelled_.empty() ? d_.before_fit : current_fit_;
    // The robot channel's figures, all against the same reference poses.
    const std::vector<Rigid>& reference = d_.after_fit.poses;
    fk_error(o_, reference, EffectParameters{}, d_.baseline);
    fk_error(o_, reference, d_.model, d_.final_error);
    for (EffectFinding& f : d_.effects) {
      fk_error(o_, reference, f.model_before, f.before);
      fk_error(o_, reference, f.accepted ? f.model_after : f.model_before, f.after);
    }
    for (EffectFinding& f : d_.outside) {
      fk_error(o_, reference, f.model_before, f.before);
      fk_error(o_, reference, f.model_after, f.after);
    }
    for (EffectFinding& f : d_.effects)
      if (f.accepted) take_from_the_final_model(f);
    for (EffectFinding& f : d_.outside) take_from_the_final_model(f);
    // A load found outside the vocabulary is structure the contract's effects do not explain.
    for (const EffectFinding& f : d_.outside) d_.unexplained.push_back(gravity_load_finding(f, time_tilt_));
    for (StructureFinding& s : find_structure(o_, d_.after_fit)) d_.unexplained.push_back(std::move(s));
    return std::move(d_);
  }

 private:
  // A trial's fit on all views (with the effect's covariance), as the nested-model and strength
  // tests judge it; the accepted one's becomes the model's fit.
  struct InSample {
    ScanModelFit fit;
    bool raised = false;  // worse than the model it extends, in its whole cost or in the images
    WaldStatistic strength;
    double strength_threshold = 0;
    bool strong_enough() const { return strength.dof == 0 || strength.chi2 > strength_threshold; }
    bool passes() const { return !raised && strong_enough(); }
  };

  struct Trial {
    Effect effect;
    HeldOut held;
    double z;
    std::vector<bool> free_spheres;  // sphere_positions: the spheres its fit frees
    bool in_vocabulary = true;
  };

  static double sum(const std::vector<double>& v) { return std::accumulate(v.begin(), v.end(), 0.0); }

  void say(const std::string& s) const {
    if (log_) log_(s);
  }

  std::vector<Effect> with(Effect e) const {
    std::vector<Effect> active = modelled_;
    active.push_back(e);
    return active;
  }

  std::vector<Trial> this_rounds_trials() const {
    std::vector<Trial> trials;
    for (Effect e : candidates_) {
      const std::vector<Effect> active = with(e);
      EffectParameters start = current_;
      if (e == Effect::sphere_positions) start.free_spheres = spheres_to_free(active);
      Trial t{e, held_out(o_, active, start), 0, start.free_spheres};
      t.z = paired_z(current_held_.cost, t.held.cost);
      say(std::string("  ") + effect_name(e) + ": held-out improvement " + std::to_string(t.z) + " standard errors");
      trials.push_back(std::move(t));
    }
    for (Effect e : outside_) {
      Trial t{e, held_out(o_, with(e), current_), 0, {}, false};
      t.z = paired_z(current_held_.cost, t.held.cost);
      say(std::string("  ") + effect_name(e) + " (outside the vocabulary): held-out improvement " + std::to_string(t.z) +
          " standard errors");
      trials.push_back(std::move(t));
    }
    return trials;
  }

  // Only spheres that stand out are candidates (offsets spread over all spheres absorb other errors
  // and noise instead); when none does, every sphere a little off (a printed holder) is the
  // holder's geometry as a whole, tried with every centre free under the gauge.
  std::vector<bool> spheres_to_free(const std::vector<Effect>& active) const {
    std::vector<bool> free = misplaced_spheres(o_, active, current_);
    if (free.empty()) {
      free.assign(o_.setup.holder.spheres_mm.size(), true);
      say("  sphere_positions: no sphere stands out from the others; every sphere tried (the holder as a whole)");
      return free;
    }
    std::string which;
    for (std::size_t k = 0; k < free.size(); ++k)
      if (free[k]) {
        which += ' ';
        which += std::to_string(k);
      }
    say("  sphere_positions: spheres standing out:" + which);
    return free;
  }

  // The scan's false-acceptance rate, spent over the rounds (round r: rate / 2^r, the sum below
  // the rate however many rounds run) and shared by the round's trials (Bonferroni): chance
  // passes any trial of any round with probability at most the rate.
  double round_threshold(std::size_t trials) {
    level_ = options_.false_acceptance_rate / std::ldexp(1.0, std::min(round_, 60)) / static_cast<double>(trials);
    return one_sided_threshold(level_, std::max<std::size_t>(o_.views.size(), 2));
  }

  int free_parameters(const Trial& t) const {
    if (t.effect != Effect::sphere_positions) return parameter_count(t.effect, o_);
    return 3 * static_cast<int>(std::count(t.free_spheres.begin(), t.free_spheres.end(), true));
  }

  // The held-out test, and a held-out chi-square lowered by more than the effect's parameter count
  // (what fitting noise alone buys on the training half): a direction the data leave nearly free
  // (a joint offset beside the base frame it repeats) can shift every held-out view the same
  // negligible way and so pass the paired test with nothing to explain.
  bool passes_held_out(const Trial& t) const {
    if (!(t.z > threshold_)) return false;
    if (!(current_held_total_ - sum(t.held.cost) > free_parameters(t))) return false;
    // Effects seen only in the image must also explain more than the detector's own systematic
    // floor (centres are biased by ~0.02 px RMS even without noise): a longer scan makes such a
    // bias "significant" without making it a physical effect.
    if (t.effect != Effect::detector_distortion && t.effect != Effect::sphere_positions) return true;
    const double explained2 = current_held_.rms_px * current_held_.rms_px - t.held.rms_px * t.held.rms_px;
    return explained2 > options_.min_image_effect_px * options_.min_image_effect_px;
  }

  // Nested models: with the effect's freedom added, the fit on all views must do at least as well
  // as the model without it, in its whole cost and in the images alone (fitted once per trial
  // that passes the rest, then remembered). A missing effect leaves the images misfitted: adding
  // it lets the robot-tied poses go where the images put them. An effect that lowers the robot
  // prior's share while the images fit worse only moves the poses away from the images: on the
  // README's example (a base offset only, a sample in the beam) a holder mount did that
  // (0.102682 -> 0.102763 px) and passed the held-out test at 4.95 standard errors, because
  // interleaved halves share whatever smooth detection bias the sample gives the spheres.
  // And the effect fitted on all views must stand from none by its own uncertainty (a Wald
  // chi-square at the round's level): an orbit null of the nuisance population passed the
  // held-out test with a distortion 1.2 standard errors from zero (t 3.76 against 3.39), a
  // pattern the interleaved halves shared but no size the fit could tell from nothing.
  const InSample& in_sample(const Trial& t) {
    if (const auto it = in_sample_.find(t.effect); it != in_sample_.end()) return it->second;
    EffectParameters start = current_;
    if (t.effect == Effect::sphere_positions) start.free_spheres = t.free_spheres;
    const std::vector<Effect> active = with(t.effect);
    InSample in;
    in.fit = fit_scan_model(o_, active, all_views(o_), start, true);
    const double cost = sum(in.fit.cost), image = sum(in.fit.image_sq_px);
    auto above = [](double after, double before) { return after > before + 1e-6 * std::max(1.0, before); };
    in.raised = above(cost, current_cost_) || above(image, current_image_);
    in.strength = effect_strength(in.fit, active, active.size() - 1);
    in.strength_threshold = in.strength.dof > 0 ? chi_square_threshold(level_, in.strength.dof) : 0.0;
    if (in.raised)
      say(std::string("  ") + effect_name(t.effect) + ": its fit on all views raises the in-sample cost (" +
          std::to_string(current_cost_) + " -> " + std::to_string(cost) + ") or the image misfit (" +
          std::to_string(current_image_) + " -> " + std::to_string(image) + " px^2): not a superset of the model");
    else if (!in.strong_enough())
      say(std::string("  ") + effect_name(t.effect) + ": fitted on all views it stands " + std::to_string(in.strength.chi2) +
          " (chi-square, " + std::to_string(in.strength.dof) + " dof) from none, under the " +
          std::to_string(in.strength_threshold) + " its round asks: no size the data tell from nothing");
    return in_sample_[t.effect] = std::move(in);
  }

  bool passes(const Trial& t) { return passes_held_out(t) && in_sample(t).passes(); }

  EffectFinding finding(const Trial& t) const {
    EffectFinding f;
    f.effect = t.effect;
    f.z = t.z;
    f.threshold_z = threshold_;
    f.model_before = current_;
    return f;
  }

  static void record_in_sample(const InSample& in, EffectFinding& f) {
    f.raised_in_sample_cost = in.raised;
    f.strength = in.strength;
    f.strength_threshold = in.strength_threshold;
  }

  // Fits `f`'s effect into the model on every view (the trial's fit, which the tests judged; its
  // value and covariance are read from the final model once the search ends).
  void add_to_model(const HeldOut& held, EffectFinding& f) {
    modelled_.push_back(f.effect);
    const InSample& in = in_sample_.at(f.effect);
    record_in_sample(in, f);
    current_fit_ = in.fit;
    current_ = current_fit_.parameters;
    current_held_ = held;
    f.model_after = current_;
    f.after = image_error(current_fit_, current_held_);
    d_.final_error = f.after;
  }

  void add_load(const Trial& load) {
    EffectFinding f = finding(load);
    f.before = d_.accepted.empty() && d_.outside.empty() ? d_.baseline : d_.final_error;
    add_to_model(load.held, f);
    say(std::string("found outside the vocabulary: ") + effect_name(load.effect) + ": " + std::to_string(f.before.rms_px) +
        " -> " + std::to_string(f.after.rms_px) + " px");
    outside_.erase(std::remove(outside_.begin(), outside_.end(), f.effect), outside_.end());
    d_.outside.push_back(std::move(f));
  }

  // The round that ends the search reports every named effect it tried, with what it would have done.
  void record_the_last_rounds_rejections(const std::vector<Trial>& trials) {
    for (const Trial& t : trials) {
      if (!t.in_vocabulary) continue;
      EffectFinding f = finding(t);
      if (const auto judged = in_sample_.find(t.effect); judged != in_sample_.end()) record_in_sample(judged->second, f);
      f.before = d_.effects.empty() && d_.outside.empty() ? d_.baseline : d_.final_error;
      f.before.heldout_rms_px = current_held_.rms_px;
      f.after = f.before;
      f.after.heldout_rms_px = t.held.rms_px;
      rejected_last_.push_back(f);
    }
  }

  void accept(const std::vector<Trial>& trials, const Trial& best) {
    std::vector<Effect> equivalent;
    for (const Trial& t : trials)
      if (t.in_vocabulary && passes(t) && paired_z(t.held.cost, best.held.cost) < options_.z_accept)
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
    if (chosen != best.effect && paired_z(trial_of(chosen).held.cost, best.held.cost) >= options_.best_lead_z)
      chosen = best.effect;
    const Trial& t = trial_of(chosen);

    EffectFinding f = finding(t);
    f.accepted = true;
    for (Effect e : equivalent)
      if (e != chosen) f.confounded_with.push_back(e);
    // A drift in time on a trajectory whose tilt changes with time is as much a load that follows
    // gravity: named beside it, not chosen between (time_and_tilt.hpp).
    if (chosen == Effect::source_drift && time_tilt_.confounded()) {
      f.confounded_with.push_back(Effect::gravity_load);
      say("  source_drift: the holder's tilt changes with time on this trajectory (correlation " +
          std::to_string(time_tilt_.correlation) + "): a load that follows gravity would look alike");
    }
    f.before = d_.accepted.empty() && d_.outside.empty() ? d_.baseline : d_.final_error;
    d_.accepted.push_back(chosen);
    if (chosen == Effect::sphere_positions) current_.free_spheres = t.free_spheres;  // as judged
    add_to_model(t.held, f);
    say(std::string("accepted ") + effect_name(chosen) + ": " + std::to_string(f.before.rms_px) + " -> " +
        std::to_string(f.after.rms_px) + " px");
    d_.effects.push_back(f);
    // The accepted effect leaves the candidates; those it was confounded with stay: where the data
    // are precise enough to tell them apart (a principal-point shift is a rotation about the focal
    // spot to first order only), the one the preference passed over may still explain what the
    // chosen one leaves, and it is then accepted beside it on the same held-out terms.
    candidates_.erase(std::remove(candidates_.begin(), candidates_.end(), chosen), candidates_.end());
  }

  // What is reported of each effect is its value in the final model, fitted with all the others
  // (a later one, a load above all, can take up part of what an earlier one first absorbed).
  void take_from_the_final_model(EffectFinding& f) const {
    const auto slot = static_cast<std::size_t>(std::find(modelled_.begin(), modelled_.end(), f.effect) - modelled_.begin());
    f.parameters = current_;
    if (current_fit_.covariance.size() > 0) {
      const int start = current_fit_.covariance_offsets[slot], size = parameter_count(f.effect, o_);
      f.covariance = current_fit_.covariance.block(start, start, size, size);
    }
  }

  const ScanObservations& o_;
  const DiagnosisOptions& options_;
  const std::function<void(const std::string&)>& log_;
  const TimeAndTilt time_tilt_;
  Diagnosis d_;
  std::vector<Effect> candidates_, outside_;
  std::vector<Effect> modelled_;  // the accepted effects and the loads found outside the vocabulary
  EffectParameters current_;
  HeldOut current_held_;
  ScanModelFit current_fit_;
  std::vector<EffectFinding> rejected_last_;
  int round_ = 0;
  // This round's: the threshold a trial must pass, the current model's totals, and which trials'
  // fits on all views raised them.
  double threshold_ = 0, level_ = 0, current_held_total_ = 0, current_cost_ = 0, current_image_ = 0;
  std::map<Effect, InSample> in_sample_;
};

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
  EffectSearch search(o, options, log);
  while (search.may_add_an_effect() && search.round()) {
  }
  return std::move(search).result();
}

bool whole_holder_off(const Diagnosis& d) {
  return std::find(d.accepted.begin(), d.accepted.end(), Effect::sphere_positions) != d.accepted.end() &&
         all_spheres_free(d.model);
}

}  // namespace ctk

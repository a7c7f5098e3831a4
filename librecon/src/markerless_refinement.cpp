#include "ctk/recon/markerless_refinement.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <numeric>
#include <optional>
#include <sstream>

#include "ctk/core/diagnosis_report.hpp"
#include "ctk/core/error.hpp"
#include "ctk/core/statistics.hpp"
#include "ctk/recon/detector_pattern.hpp"
#include "ctk/recon/disjoint_parts.hpp"

namespace ctk {

namespace {

constexpr double kDeg = M_PI / 180.0;

struct State {
  GlobalGeometry geometry;
  ForwardModel model;
};

// One fitted parameter of a candidate: where it lives in the model, its scan step, the range a
// physical value may take (an estimate at its edge is a sign the candidate absorbs something else)
// and how it is reported.
struct Knob {
  std::string key;
  double step, lower, upper;
  std::function<double&(State&)> value;
  double report_scale = 1.0;   // internal value * scale = reported value
  double report_offset = 0.0;  // added after scaling (the nominal principal point for u0/v0)
};

struct Candidate {
  std::string name;
  bool changes_geometry;  // else it changes the forward model only
  std::vector<Knob> knobs;
  // A fixed detector pattern (pixel_gain, column_gain) is fitted in closed form from the fit
  // views' residuals instead of by knobs: one value per pixel, or per column.
  enum class Pattern { none, per_pixel, per_column } pattern = Pattern::none;
};

// What a detector of one row cannot observe: every ray lies in the orbit's plane, so moving the
// row across it (v0), turning it in its plane (a roll lifts its ends out of the plane) or tilting
// the axis changes nothing the row sees to first order.
const std::vector<std::pair<std::string, std::string>> kUnobservableOnOneRow = {
    {"v0_px", "one detector row: its height is not seen (every ray lies in the orbit's plane)"},
    {"detector_roll", "one detector row: a roll moves its ends out of the orbit's plane, which the row does not see"},
    {"axis_tilt", "one detector row: a tilt of the axis moves the slice, which the row does not see"},
    {"pixel_gain", "one detector row: each pixel is a column, so column_gain measures it"}};

bool unobservable_on_one_row(const std::string& name) {
  return std::any_of(kUnobservableOnOneRow.begin(), kUnobservableOnOneRow.end(), [&](const auto& u) { return u.first == name; });
}

std::vector<Candidate> make_candidates(const Eigen::Vector2d& nominal_pp, const RefinementOptions& o, bool one_row) {
  const double arc = o.nominal_blur_arc_deg > 0 ? o.nominal_blur_arc_deg : 2.0;
  std::vector<Candidate> all = {
      {"detector_offset",
       true,
       {{"u0_px", 0.5, -10, 10, [](State& s) -> double& { return s.geometry.du_px; }, 1.0, nominal_pp.x()},
        {"v0_px", 0.5, -10, 10, [](State& s) -> double& { return s.geometry.dv_px; }, 1.0, nominal_pp.y()}}},
      {"detector_roll",
       true,
       {{"roll_deg", 0.1 * kDeg, -2 * kDeg, 2 * kDeg, [](State& s) -> double& { return s.geometry.roll_rad; }, 1 / kDeg}}},
      {"axis_tilt",
       true,
       {{"tilt_deg", 0.25 * kDeg, -2 * kDeg, 2 * kDeg, [](State& s) -> double& { return s.geometry.tilt_rad; }, 1 / kDeg}}},
      {"magnification", true, {{"sdd_scale", 0.005, 0.97, 1.03, [](State& s) -> double& { return s.geometry.sdd_scale; }}}},
      {"angular_blur",
       false,
       {{"arc_deg", arc / 4 * kDeg, 0.0, 2 * arc * kDeg, [](State& s) -> double& { return s.model.blur_arc_rad; }, 1 / kDeg}}},
      {"beam_hardening", false, {{"c2", 0.03, -0.2, 0.2, [](State& s) -> double& { return s.model.hardening_c2; }}}},
      {"pixel_gain", false, {}, Candidate::Pattern::per_pixel},
      {"column_gain", false, {}, Candidate::Pattern::per_column},
  };
  std::vector<Candidate> chosen;
  for (const auto& name : o.candidates) {
    auto it = std::find_if(all.begin(), all.end(), [&](const Candidate& c) { return c.name == name; });
    if (it == all.end()) throw std::invalid_argument("markerless refinement: unknown effect '" + name + "'");
    if (one_row && unobservable_on_one_row(it->name)) continue;
    chosen.push_back(*it);
    if (one_row) std::erase_if(chosen.back().knobs, [](const Knob& k) { return unobservable_on_one_row(k.key); });
  }
  return chosen;
}

bool contains(const std::vector<std::string>& v, const std::string& x) { return std::find(v.begin(), v.end(), x) != v.end(); }

double sum(const std::vector<double>& v) { return std::accumulate(v.begin(), v.end(), 0.0); }
double rms(const std::vector<double>& mean_squares) {
  return std::sqrt(sum(mean_squares) / static_cast<double>(mean_squares.size()));
}

struct KnobFit {
  double value = 0;
  double standard_error = std::numeric_limits<double>::quiet_NaN();  // unknown when the cost is not a parabola
  bool at_edge = false;                                              // the cost kept falling to the end of the allowed range
  // The vertex from the first and from the second half of the fit views in time: what moves
  // during the scan (the object settling, the stage) parts them, which the jackknife over single
  // views does not see.
  double halves[2] = {std::numeric_limits<double>::quiet_NaN(), std::numeric_limits<double>::quiet_NaN()};
};

// Scans one knob over five settings on the fit views, moving the window (by at most its width)
// until the cost's minimum lies inside it (or the knob's range ends); the value is the vertex of
// the parabola through the five, the standard error a jackknife over the fit views.
KnobFit fit_knob(const ConsistencyProbe& probe, State state, const Knob& knob) {
  const double span = 4 * knob.step;
  double first = std::clamp(knob.value(state) - 2 * knob.step, knob.lower, knob.upper - span);
  KnobFit out;
  bool symmetrised = false;
  constexpr int kScans = 8;  // windows scanned at most (a window spans four steps)
  for (int scan = 0; scan < kScans; ++scan) {
    std::vector<double> x;
    std::vector<std::vector<double>> per_view;
    for (int i = 0; i < 5; ++i) {
      x.push_back(first + i * knob.step);
      knob.value(state) = x.back();
      per_view.push_back(probe.fit_costs(state.geometry, state.model));
    }
    std::vector<double> total;
    total.reserve(per_view.size());
    for (const auto& c : per_view) total.push_back(sum(c));
    const auto lowest = static_cast<std::size_t>(std::min_element(total.begin(), total.end()) - total.begin());
    double vertex = parabola_vertex(x, total);
    if (std::isnan(vertex)) vertex = x[lowest];
    // The minimum lies beyond an end of the window when the cost falls towards that end.
    const int beyond = lowest == 0 && vertex <= x.front() ? -1 : lowest + 1 == x.size() && vertex >= x.back() ? +1 : 0;
    const bool window_at_bound =
        (beyond < 0 && x.front() <= knob.lower + 1e-12) || (beyond > 0 && x.back() >= knob.upper - 1e-12);
    if (beyond != 0 && !window_at_bound && scan < kScans - 1) {
      // Far from its minimum a cost is rarely a parabola (a misplaced axis doubles edges: the
      // cost grows about linearly), so an extrapolated vertex may lie anywhere: move the window
      // towards it by at most its own width.
      const double towards = std::clamp(vertex, x.front() - span, x.back() + span);
      first = std::clamp(towards - 2 * knob.step, knob.lower, knob.upper - span);
      continue;
    }
    out.value = std::clamp(vertex, knob.lower, knob.upper);
    out.at_edge = window_at_bound || out.value <= knob.lower + 0.5 * knob.step || out.value >= knob.upper - 0.5 * knob.step;
    // A parabola sampled lopsidedly about its vertex is biased where the cost is not exactly
    // quadratic: scan once more, centred on the vertex (once only: a weakly observable knob's
    // vertex wanders on a flat cost, and chasing it would walk it anywhere).
    if (!symmetrised && !out.at_edge && std::abs(vertex - x[2]) > 0.25 * knob.step && scan < kScans - 1) {
      symmetrised = true;
      first = std::clamp(vertex - 2 * knob.step, knob.lower, knob.upper - span);
      continue;
    }
    // Jackknife: leave one fit view out, refit the vertex.
    const std::size_t n = per_view.front().size();
    std::vector<double> leave_one;
    for (std::size_t k = 0; k < n; ++k) {
      std::vector<double> t;
      for (std::size_t i = 0; i < per_view.size(); ++i) t.push_back(total[i] - per_view[i][k]);
      const double v = parabola_vertex(x, t);
      if (!std::isnan(v)) leave_one.push_back(v);
    }
    if (leave_one.size() > 2) {
      const double mean = sum(leave_one) / static_cast<double>(leave_one.size());
      double ss = 0;
      for (double v : leave_one) ss += (v - mean) * (v - mean);
      out.standard_error = std::sqrt(ss * static_cast<double>(leave_one.size() - 1) / static_cast<double>(leave_one.size()));
    }
    // The fit views are in scan order: the halves in time.
    for (int half = 0; half < 2; ++half) {
      std::vector<double> t(per_view.size(), 0.0);
      for (std::size_t i = 0; i < per_view.size(); ++i)
        for (std::size_t k = half == 0 ? 0 : n / 2; k < (half == 0 ? n / 2 : n); ++k) t[i] += per_view[i][k];
      out.halves[half] = parabola_vertex(x, t);
    }
    break;
  }
  return out;
}

// Its implicit moves are noexcept (every member's is); clang-tidy reads a throw into nlohmann::json's.
// NOLINTNEXTLINE(bugprone-exception-escape)
struct Trial {
  State after;
  RefinedEffect effect;
  std::vector<double> judge_after;
  bool at_edge = false;
  bool undetermined = false;  // the cost showed no minimum with positive curvature
  // A per-pixel offset cannot smooth the object, so the edge-blur rule (against effects that
  // compensate the yardstick's blur) does not apply; removing a ring even lowers the measure.
  bool can_blur = true;
};

// A fixed detector pattern, from the measurements alone: the fine part (along the row) of their
// mean over every view but the judge views, per pixel or per column. Fitting it to the residuals
// instead would take up the yardstick's own errors, which are fixed on the detector too (a
// noise-free simulation of a perfect detector got 0.8 % of its largest line integral that way).
// Its noise: half the difference between the fine parts of two halves of those views.
Trial fit_detector_pattern(const ConsistencyProbe& probe, const State& current, const std::vector<double>& judge_before,
                           const Candidate& candidate, const std::function<void(const std::string&)>& log) {
  Trial t;
  t.after = current;
  t.can_blur = false;
  t.effect.name = candidate.name;
  const bool by_column = candidate.pattern == Candidate::Pattern::per_column;
  const Detector& d = probe.detector();
  std::vector<int> views, halves[2];
  for (const auto* part : {&probe.split().reconstruct, &probe.split().fit}) views.insert(views.end(), part->begin(), part->end());
  std::sort(views.begin(), views.end());
  for (std::size_t i = 0; i < views.size(); ++i) halves[i % 2].push_back(views[i]);
  const DetectorPattern pattern = mean_pattern(probe.measured(), views, probe.row_margin(), by_column);
  std::vector<float>& offset = t.after.model.pixel_offset;
  offset = fine_part(pattern);
  const std::vector<float> a = fine_part(mean_pattern(probe.measured(), halves[0], probe.row_margin(), by_column)),
                           b = fine_part(mean_pattern(probe.measured(), halves[1], probe.row_margin(), by_column));
  // Its size: RMS over the values (columns or pixels), less the noise each carries.
  double sum2 = 0, noise2 = 0, largest = 0;
  std::size_t values = 0, at = 0;
  const auto cols = static_cast<std::size_t>(d.cols);
  const auto first_row = static_cast<std::size_t>(std::min(probe.row_margin(), (d.rows - 1) / 2));
  for (std::size_t i = 0; i < offset.size(); ++i) {
    if (!pattern.used[i] || (by_column && i / cols != first_row)) continue;  // a column's value once
    sum2 += double(offset[i]) * offset[i];
    noise2 += 0.25 * (double(a[i]) - b[i]) * (double(a[i]) - b[i]);
    if (std::abs(offset[i]) > std::abs(largest)) largest = offset[i], at = i;
    ++values;
  }
  const double n = static_cast<double>(std::max<std::size_t>(values, 1));
  const double noise = std::sqrt(noise2 / n);
  t.effect.parameters = {{by_column ? "columns" : "pixels", values},
                         {"pattern_rms", std::sqrt(std::max(sum2 / n - noise2 / n, 0.0))},
                         {"largest", largest},
                         {"largest_at_column", static_cast<int>(at % cols)}};
  if (!by_column) t.effect.parameters["largest_at_row"] = static_cast<int>(at / cols);
  t.effect.uncertainty = {{"pattern_rms", noise}, {"largest", noise}};
  t.effect.note = std::string("line-integral offsets fixed on the detector, measured - true (") +
                  (by_column ? "one per column: a defective column, a line detector's column gains"
                             : "one per pixel: each pixel's gain differs between flat and projections") +
                  "): the mean over the non-judge views less a parabola through the 3 neighbours on either side along the row";
  t.judge_after = probe.judge_costs(t.after.geometry, t.after.model);
  t.effect.heldout_rms_before = rms(judge_before);
  t.effect.heldout_rms_after = rms(t.judge_after);
  t.effect.z = paired_z(judge_before, t.judge_after);
  if (log) {
    std::ostringstream line;
    line << candidate.name << ": pattern RMS " << t.effect.parameters["pattern_rms"].get<double>() << " (noise " << noise
         << "), largest " << largest << "; held-out RMS " << t.effect.heldout_rms_before << " -> " << t.effect.heldout_rms_after
         << " (z " << t.effect.z << ")";
    log(line.str());
  }
  return t;
}

// `starts`: where a knob's scan begins (reported units) while the model still has its nominal value.
Trial try_candidate(const ConsistencyProbe& probe, const State& current, const std::vector<double>& judge_before,
                    const Candidate& candidate, const std::map<std::string, double>& starts,
                    const std::function<void(const std::string&)>& log) {
  Trial t;
  t.after = current;
  t.effect.name = candidate.name;
  std::vector<std::pair<const Knob*, KnobFit>> fits;
  // A knob whose cost shows no curved minimum is not measured: it keeps its value. The candidate
  // is a measurement only if at least one of its knobs is.
  int measured = 0;
  std::string unmeasured;
  for (const Knob& knob : candidate.knobs) {
    State start = t.after, nominal;
    if (const auto it = starts.find(knob.key); it != starts.end() && knob.value(start) == knob.value(nominal))
      knob.value(start) = std::clamp((it->second - knob.report_offset) / knob.report_scale, knob.lower, knob.upper);
    KnobFit f = fit_knob(probe, start, knob);
    if (std::isnan(f.standard_error) && !f.at_edge) {
      f.value = knob.value(t.after);
      unmeasured += (unmeasured.empty() ? "" : ", ") + knob.key;
    } else {
      ++measured;
    }
    knob.value(t.after) = f.value;
    fits.emplace_back(&knob, f);
  }
  t.undetermined = measured == 0;
  if (!unmeasured.empty())
    t.effect.note =
        "no well-curved minimum of the held-out cost in " + unmeasured +
        (t.undetermined ? ": not a measurement, so not accepted" : ": not observable here, kept at its starting value");
  if (candidate.name == "detector_offset" && candidate.knobs.size() > 1)
    t.effect.note += std::string(t.effect.note.empty() ? "" : "; ") +
                     "v0 (the central row) is weakly observable in a circular scan: its uncertainty is the view-to-view "
                     "scatter only and does not include the yardstick's systematic error";
  t.judge_after = probe.judge_costs(t.after.geometry, t.after.model);
  t.effect.heldout_rms_before = rms(judge_before);
  t.effect.heldout_rms_after = rms(t.judge_after);
  t.effect.z = paired_z(judge_before, t.judge_after);
  std::ostringstream line;
  line << candidate.name << ":";
  for (const auto& [knob, f] : fits) {
    const double reported = f.value * knob->report_scale + knob->report_offset;
    t.effect.parameters[knob->key] = reported;
    t.effect.uncertainty[knob->key] = f.standard_error * std::abs(knob->report_scale);
    if (std::isfinite(f.halves[0]) && std::isfinite(f.halves[1]) && std::isfinite(f.standard_error))
      t.effect.halves_in_time[knob->key] = disjoint_parts_json(f.halves[0] * knob->report_scale + knob->report_offset,
                                                               f.halves[1] * knob->report_scale + knob->report_offset,
                                                               f.standard_error * std::abs(knob->report_scale));
    line << " " << knob->key << " " << reported << " +- " << f.standard_error * std::abs(knob->report_scale);
    if (f.at_edge) {
      t.at_edge = true;
      t.effect.note =
          "the fit ran to the end of the physically plausible range: the candidate absorbs something else "
          "(the coarse prediction's own blur or streaks), so it is not accepted";
    }
  }
  line << "; held-out RMS " << t.effect.heldout_rms_before << " -> " << t.effect.heldout_rms_after << " (z " << t.effect.z << ")";
  if (log) log(line.str());
  return t;
}

// Among the eligible trials (best first), the first whose reconstruction keeps its edges: one that
// blurs them (beyond `sharpness_tolerance`) compensates the yardstick's own errors, not the
// geometry, and is dropped with that note. The winner's volume and sharpness are kept.
std::optional<std::size_t> first_that_keeps_edges(const ConsistencyProbe& probe, const VolumeLayout& fine,
                                                  const RefinementOptions& options, const std::vector<std::size_t>& eligible,
                                                  std::vector<Trial>& trials, std::vector<bool>& dropped, double& sharpness,
                                                  Volume& volume_after, const std::function<void(const std::string&)>& log) {
  for (std::size_t i : eligible) {
    Volume after = probe.reconstruct_all(trials[i].after.geometry, trials[i].after.model, fine);
    const double s_after = edge_sharpness(after);
    if (trials[i].can_blur && s_after < (1 - options.sharpness_tolerance) * sharpness) {
      trials[i].effect.note = "held-out views improve, but the reconstruction's edges blur (sharpness " +
                              std::to_string(sharpness) + " -> " + std::to_string(s_after) +
                              " per mm): the candidate compensates the yardstick, not the geometry";
      dropped[i] = true;
      if (log) log("not accepted " + trials[i].effect.name + ": " + trials[i].effect.note);
      continue;
    }
    trials[i].effect.sharpness_before = sharpness;
    trials[i].effect.sharpness_after = s_after;
    volume_after = std::move(after);
    sharpness = s_after;
    return i;
  }
  return std::nullopt;
}

// The candidates tried again next round: not the winner, not those whose fit ran to the edge, had
// no minimum or blurred the volume, nor, once a detector pattern is in the model, the other
// description of it (it would replace it); those go to `rejected`, as all do in the last round.
std::vector<Candidate> still_to_try(const std::vector<Candidate>& remaining, std::vector<Trial>& trials, std::size_t winner,
                                    const std::vector<bool>& dropped, bool last_round, std::vector<RefinedEffect>& rejected) {
  const Trial& win = trials[winner];
  const bool pattern_won = remaining[winner].pattern != Candidate::Pattern::none;
  std::vector<Candidate> next;
  for (std::size_t i = 0; i < trials.size(); ++i) {
    if (i == winner) continue;
    const bool alternative = pattern_won && remaining[i].pattern != Candidate::Pattern::none;
    if (alternative)
      trials[i].effect.note = "another description of the detector pattern, which " + win.effect.name + " describes in the model";
    if (alternative || dropped[i] || trials[i].at_edge || trials[i].undetermined || last_round)
      rejected.push_back(trials[i].effect);
    else
      next.push_back(remaining[i]);
  }
  return next;
}

RefinedEffect with_rejection_note(RefinedEffect e) {
  if (e.note.empty()) e.note = "the held-out views do not improve beyond chance";
  if (e.name == "angular_blur")
    e.note +=
        "; in a circular scan at constant speed, views blurred over an arc are exact projections of the "
        "rotation-averaged object, so blur is not observable by consistency, only in resolution";
  return e;
}

// A fixed detector pattern the model misses shows as a per-pixel mean residual over the judge
// views far outside its standard error.
void find_residual_pattern(const ConsistencyProbe& probe, const State& state, RefinementResult& result) {
  ProjectionStack residuals;
  probe.judge_costs(state.geometry, state.model, &residuals);
  std::vector<int> all(static_cast<std::size_t>(residuals.views));
  std::iota(all.begin(), all.end(), 0);
  result.residual_pattern = mean_pattern(residuals, all, probe.row_margin(), false, -1.0);
  const double pattern = pattern_statistic(result.residual_pattern);
  result.structured = pattern > 2.0;
  std::ostringstream note;
  note << "fixed detector pattern of the held-out residual: mean (mean/se)^2 per pixel over the judge views " << pattern
       << " (about 1 when there is none)";
  result.unexplained_note = note.str();
}

}  // namespace

void RefinementOptions::validate() const {
  require_option(z_accept > 0, "RefinementOptions.z_accept", "a number above 0", z_accept);
  require_option(max_rounds >= 1, "RefinementOptions.max_rounds", "at least 1", max_rounds);
  require_option(sharpness_tolerance >= 0 && sharpness_tolerance < 1, "RefinementOptions.sharpness_tolerance",
                 "a number in [0, 1)", sharpness_tolerance);
  require_option(nominal_blur_arc_deg >= 0, "RefinementOptions.nominal_blur_arc_deg", "at least 0", nominal_blur_arc_deg);
}

RefinementResult refine_markerless(const ConsistencyProbe& probe, const VolumeLayout& fine, const RefinementOptions& options,
                                   const std::function<void(const std::string&)>& log) {
  options.validate();
  RefinementResult result;
  result.views = static_cast<int>(probe.split().reconstruct.size() + probe.split().fit.size() + probe.split().judge.size());
  State state;
  // The yardstick's own resolution first: how much smoothing the nominal prediction wants.
  const Knob smoothing{"prediction_smoothing", 0.2, 0.0, 1.0, [](State& s) -> double& { return s.model.prediction_smoothing; }};
  state.model.prediction_smoothing = fit_knob(probe, state, smoothing).value;
  result.prediction_smoothing = state.model.prediction_smoothing;
  if (log) log("yardstick: prediction smoothing " + std::to_string(state.model.prediction_smoothing));
  std::vector<double> judge = probe.judge_costs(state.geometry, state.model);
  result.heldout_rms_before = rms(judge);
  result.volume_before = probe.reconstruct_all(state.geometry, state.model, fine);
  double sharpness = edge_sharpness(result.volume_before);
  result.sharpness_before = sharpness;
  if (log) {
    std::ostringstream s;
    s << "nominal model: held-out RMS " << result.heldout_rms_before << ", sharpness " << sharpness << " per mm";
    log(s.str());
  }

  const bool one_row = probe.detector().rows == 1;
  if (one_row)
    for (const auto& [what, why] : kUnobservableOnOneRow)
      if (what == "v0_px" ? contains(options.candidates, "detector_offset") : contains(options.candidates, what))
        result.not_observable.push_back({what, why});
  std::vector<Candidate> remaining = make_candidates(probe.nominal_principal_point(), options, one_row);
  std::vector<RefinedEffect> rejected;
  for (int round = 1; round <= options.max_rounds && !remaining.empty(); ++round) {
    if (log) log("round " + std::to_string(round) + ": trying " + std::to_string(remaining.size()) + " effects");
    std::vector<Trial> trials;
    trials.reserve(remaining.size());
    for (const Candidate& c : remaining)
      trials.push_back(c.pattern != Candidate::Pattern::none ? fit_detector_pattern(probe, state, judge, c, log)
                                                             : try_candidate(probe, state, judge, c, options.knob_starts, log));
    // The eligible candidate that lowers the held-out RMS most joins the model, unless it blurs
    // the reconstruction (beyond `sharpness_tolerance`): a true geometric correction does not,
    // one that compensates the yardstick's own errors may.
    std::vector<std::size_t> eligible;
    for (std::size_t i = 0; i < trials.size(); ++i)
      if (trials[i].effect.z > options.z_accept && !trials[i].at_edge && !trials[i].undetermined) eligible.push_back(i);
    std::sort(eligible.begin(), eligible.end(), [&](std::size_t a, std::size_t b) {
      return trials[a].effect.heldout_rms_after < trials[b].effect.heldout_rms_after;
    });
    std::vector<bool> dropped(trials.size(), false);
    const std::optional<std::size_t> winner =
        first_that_keeps_edges(probe, fine, options, eligible, trials, dropped, sharpness, result.volume_after, log);
    if (!winner) {
      for (auto& t : trials) rejected.push_back(t.effect);
      remaining.clear();
      break;
    }
    Trial& win = trials[*winner];
    win.effect.accepted = true;
    win.effect.round = round;
    // Others that pass too and predict the judge views as well as the winner, within noise.
    for (std::size_t i : eligible)
      if (i != *winner && !dropped[i] && std::abs(paired_z(trials[i].judge_after, win.judge_after)) < options.z_accept)
        win.effect.confounded_with.push_back(trials[i].effect.name);
    state = win.after;
    judge = win.judge_after;
    if (log)
      log("accepted " + win.effect.name + "; sharpness " + std::to_string(win.effect.sharpness_before) + " -> " +
          std::to_string(sharpness));
    result.effects.push_back(win.effect);
    remaining = still_to_try(remaining, trials, *winner, dropped, round == options.max_rounds, rejected);
  }
  for (RefinedEffect& e : rejected) result.effects.push_back(with_rejection_note(std::move(e)));
  result.geometry = state.geometry;
  result.model = state.model;
  result.heldout_rms_after = rms(judge);
  result.sharpness_after = sharpness;
  if (result.volume_after.data.empty()) result.volume_after = result.volume_before;

  find_residual_pattern(probe, state, result);
  return result;
}

nlohmann::json refinement_to_json(const RefinementResult& r) {
  using nlohmann::json;
  DiagnosisReport report;
  report.mode = "markerless";
  for (const auto& e : r.effects) {
    ReportedEffect reported{e.name, e.accepted, e.z, e.parameters, e.uncertainty, e.confounded_with, json::object()};
    json& j = reported.figures;
    j["heldout_projection_rms_before"] = e.heldout_rms_before;
    j["heldout_projection_rms_after"] = e.heldout_rms_after;
    if (e.accepted) {
      j["round"] = e.round;
      j["sharpness_per_mm_before"] = e.sharpness_before;
      j["sharpness_per_mm_after"] = e.sharpness_after;
    }
    if (!e.halves_in_time.empty()) j["halves_in_time"] = e.halves_in_time;
    if (!e.note.empty()) j["note"] = e.note;
    report.effects.push_back(std::move(reported));
  }
  json not_observable = json::array();
  for (const auto& [what, why] : r.not_observable) not_observable.push_back({{"parameter", what}, {"reason", why}});
  report.baseline = {
      {"views_ok", r.views}, {"heldout_projection_rms", r.heldout_rms_before}, {"sharpness_per_mm", r.sharpness_before}};
  report.final_error = {{"heldout_projection_rms", r.heldout_rms_after}, {"sharpness_per_mm", r.sharpness_after}};
  report.structured = r.structured;
  report.unexplained_note = r.unexplained_note;
  report.criterion =
      "fitted on views 1 mod 4, judged on views 3 mod 4 of a reconstruction from the even views; accepted when the mean "
      "per-view held-out cost falls by more than z standard errors of the paired differences";
  report.extra = {{"yardstick", {{"prediction_smoothing", r.prediction_smoothing}}}, {"not_observable", not_observable}};
  return report.to_json();
}

}  // namespace ctk

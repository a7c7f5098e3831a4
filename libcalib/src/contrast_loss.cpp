#include "ctk/calib/contrast_loss.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <sstream>

namespace ctk {

namespace {

// Between trial rates: the agreement's minimum is about 0.3 wide on the reference holder's
// polychromatic orbits, so three trials span it.
constexpr double kStep = 0.2;

// Per (view, sphere) used by a calibrated view: its squared reprojection residual.
using Residuals = std::map<std::pair<int, int>, double>;

Residuals residuals_by_sphere(const ScanCalibration& c) {
  Residuals out;
  for (std::size_t v = 0; v < c.views.size(); ++v) {
    const ViewCalibration& view = c.views[v];
    if (view.status != ViewStatus::ok) continue;
    for (std::size_t k = 0; k < view.spheres.size(); ++k)
      out[{static_cast<int>(v), view.spheres[k]}] = (view.detected_px[k] - view.fitted_px[k]).squaredNorm();
  }
  return out;
}

// The agreement of each trial: the mean squared residual over the (view, sphere) pairs every
// trial used. Which spheres a view keeps changes with the rate, and a view's mean with it (over
// each trial's own spheres it jumped by more than the rate moved it). Spheres some trial lost do
// not count, even where they say most.
struct Agreement {
  std::vector<double> mean_squared;  // per trial; HUGE_VAL when no pair is common
  int spheres = 0, views = 0;        // the common pairs, and the views they are in
};

Agreement agreement_over_common_pairs(const std::vector<Residuals>& residuals) {
  std::vector<std::pair<int, int>> common;
  for (const auto& entry : residuals.front()) {
    const std::pair<int, int> key = entry.first;
    if (std::all_of(residuals.begin(), residuals.end(), [&key](const Residuals& r) { return r.contains(key); }))
      common.push_back(key);
  }
  Agreement a;
  a.mean_squared.assign(residuals.size(), HUGE_VAL);
  for (std::size_t t = 0; t < residuals.size() && !common.empty(); ++t) {
    double sum = 0;
    for (const auto& key : common) sum += residuals[t].at(key);
    a.mean_squared[t] = sum / static_cast<double>(common.size());
  }
  a.spheres = static_cast<int>(common.size());
  int previous = -1;
  for (const auto& key : common)  // ordered by view
    if (key.first != previous) {
      ++a.views;
      previous = key.first;
    }
  return a;
}

// A parabola through the best trial and its neighbours (the first three when 0 is best): its
// vertex is the rate, its curvature the information. The summed squares are N S(rate) over N
// spheres (2N numbers less 6 per view's pose); one standard error moves them by the residual
// variance per number. A vertex at or below zero gives 0, not used.
void place_by_parabola(std::size_t best, ContrastLossMeasurement& m) {
  const std::vector<double>& rates = m.trial_rates;
  const std::vector<double>& agreement = m.mean_squared_px2;
  const std::size_t mid = std::max<std::size_t>(best, 1);
  const double x0 = rates[mid - 1], x1 = rates[mid], x2 = rates[mid + 1];
  const double y0 = agreement[mid - 1], y1 = agreement[mid], y2 = agreement[mid + 1];
  const double slope01 = (y1 - y0) / (x1 - x0), curvature = ((y2 - y1) / (x2 - x1) - slope01) / (x2 - x0);  // S'' / 2
  if (!(curvature > 0)) return;
  const double vertex = 0.5 * (x0 + x1) - slope01 / (2 * curvature);
  if (vertex <= 0) {
    m.rate = 0;
    return;
  }
  m.rate = vertex;
  const double least = y0 + slope01 * (vertex - x0) + curvature * (vertex - x0) * (vertex - x1);
  const double freedom = 2.0 * m.spheres - 6.0 * m.views;
  if (freedom <= 0) return;
  const double variance = least * m.spheres / freedom;
  m.sigma = std::sqrt(variance / (m.spheres * curvature));
  m.used = true;
}

}  // namespace

std::vector<int> contrast_sample_views(int projections, int count) {
  std::vector<int> views;
  const int n = std::min(projections, count);
  views.reserve(static_cast<std::size_t>(std::max(n, 0)));
  for (int k = 0; k < n; ++k) views.push_back(static_cast<int>((k + 0.5) * projections / n));
  return views;
}

ContrastLossMeasurement measure_contrast_loss(const std::function<ScanCalibration(const CalibrationOptions&)>& calibrate_sample,
                                              const CalibrationOptions& options) {
  std::vector<double> rates;  // the trials, in increasing order
  std::vector<Residuals> residuals;
  const auto try_rate = [&](double rate) {
    CalibrationOptions o = options;
    o.contrast_loss = rate;
    const auto at = static_cast<std::size_t>(std::lower_bound(rates.begin(), rates.end(), rate) - rates.begin());
    rates.insert(rates.begin() + static_cast<std::ptrdiff_t>(at), rate);
    residuals.insert(residuals.begin() + static_cast<std::ptrdiff_t>(at), residuals_by_sphere(calibrate_sample(o)));
  };
  // Trials at 0 and one step, then a step beyond the last while it agrees better than the one
  // before (within the range); then half a step either side of the best (only above it when 0 is
  // best). A ball's contrast only falls where more is in the way (hardening and scatter both lower
  // it), so no rate below zero is tried: a vertex below zero stands for another error of the model
  // (a monochromatic orbit of 1.3 px spheres measured -0.22 and let a holder mount lead the README
  // example's base offset).
  int highest = 1;  // the coarse trials' end, in steps
  const int most = static_cast<int>(std::floor(kMostContrastLoss / kStep + 1e-9));
  try_rate(0);
  try_rate(kStep);
  bool refined = false;
  Agreement a;
  while (true) {
    a = agreement_over_common_pairs(residuals);
    const std::size_t last = rates.size() - 1;
    const auto best =
        static_cast<std::size_t>(std::min_element(a.mean_squared.begin(), a.mean_squared.end()) - a.mean_squared.begin());
    if (!refined && best == last && highest < most) {
      try_rate(++highest * kStep);
    } else if (!refined && best + 1 < rates.size()) {
      refined = true;  // half steps about the coarse minimum
      const double at = rates[best];
      if (best > 0) try_rate(at - kStep / 2);
      try_rate(at + kStep / 2);
    } else {
      break;
    }
  }
  ContrastLossMeasurement m;
  m.sigma = HUGE_VAL;
  m.trial_rates = rates;
  m.mean_squared_px2 = a.mean_squared;
  m.views = a.views;
  m.spheres = a.spheres;
  const auto best =
      static_cast<std::size_t>(std::min_element(a.mean_squared.begin(), a.mean_squared.end()) - a.mean_squared.begin());
  m.rate = rates[best];
  if (m.views == 0 || !refined || best + 1 == rates.size()) return m;  // nothing calibrated, or the range's end
  place_by_parabola(best, m);
  return m;
}

nlohmann::json to_json(const ContrastLossMeasurement& m) {
  nlohmann::json trials = nlohmann::json::array();
  for (std::size_t t = 0; t < m.trial_rates.size(); ++t)
    trials.push_back({{"rate", m.trial_rates[t]}, {"mean_squared_px2", m.mean_squared_px2[t]}});
  return {{"rate_per_line_integral", m.rate},
          {"sigma", std::isfinite(m.sigma) ? nlohmann::json(m.sigma) : nlohmann::json()},
          {"used", m.used},
          {"views", m.views},
          {"spheres", m.spheres},
          {"trials", trials}};
}

std::string contrast_loss_line(const ContrastLossMeasurement& m) {
  std::ostringstream line;
  line.precision(2);
  line << "spheres' contrast loss over their background: " << m.rate;
  if (std::isfinite(m.sigma)) line << " +- " << m.sigma;
  line << " per unit line integral (" << m.views << " sample views), "
       << (m.used ? "modelled in every sphere's profile fit"
                  : "not modelled (the spheres' agreement has no minimum within reach)");
  return line.str();
}

}  // namespace ctk

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

// Per view calibrated: its squared residuals summed over its spheres, and how many spheres.
using ViewResiduals = std::map<int, std::pair<double, int>>;

ViewResiduals residuals_by_view(const ScanCalibration& c) {
  ViewResiduals out;
  for (std::size_t v = 0; v < c.views.size(); ++v) {
    const ViewCalibration& view = c.views[v];
    if (view.status == ViewStatus::ok && view.spheres_used > 0)
      out[static_cast<int>(v)] = {view.rms_px * view.rms_px * view.spheres_used, view.spheres_used};
  }
  return out;
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
  std::vector<double> rates;
  std::vector<ViewResiduals> residuals;
  const auto try_rate = [&](double rate, bool at_front) {
    CalibrationOptions o = options;
    o.contrast_loss = rate;
    ViewResiduals r = residuals_by_view(calibrate_sample(o));
    rates.insert(at_front ? rates.begin() : rates.end(), rate);
    residuals.insert(at_front ? residuals.begin() : residuals.end(), std::move(r));
  };
  ContrastLossMeasurement m;
  std::vector<double> agreement;
  std::size_t best = 0;
  int spheres = 0;
  // Trials at 0 and one step, then a step beyond an end that agrees better than its neighbour
  // until neither does (or the range ends). The agreement is judged on the views every trial
  // calibrated.
  int lowest = 0, highest = 1;  // the trials' rates in steps
  const int most = static_cast<int>(std::floor(kMostContrastLoss / kStep + 1e-9));
  try_rate(0, false);
  try_rate(kStep, false);
  while (true) {
    std::vector<int> common;
    for (const auto& entry : residuals.front()) {
      const int v = entry.first;
      if (std::all_of(residuals.begin(), residuals.end(), [v](const ViewResiduals& r) { return r.contains(v); }))
        common.push_back(v);
    }
    agreement.assign(rates.size(), HUGE_VAL);
    std::vector<int> used(rates.size(), 0);
    for (std::size_t t = 0; t < rates.size(); ++t) {
      double sum = 0;
      for (int v : common) {
        sum += residuals[t].at(v).first;
        used[t] += residuals[t].at(v).second;
      }
      if (used[t] > 0) agreement[t] = sum / used[t];
    }
    best = static_cast<std::size_t>(std::min_element(agreement.begin(), agreement.end()) - agreement.begin());
    m.views = static_cast<int>(common.size());
    spheres = used[best];
    const std::size_t last = rates.size() - 1;
    if (agreement[0] < agreement[1] && lowest > -most)
      try_rate(--lowest * kStep, true);
    else if (agreement[last] < agreement[last - 1] && highest < most)
      try_rate(++highest * kStep, false);
    else
      break;
  }
  m.trial_rates = rates;
  m.mean_squared_px2 = agreement;
  m.spheres = spheres;
  m.rate = rates[best];
  m.sigma = HUGE_VAL;
  if (m.views == 0 || best == 0 || best + 1 == rates.size()) return m;  // nothing calibrated, or the range's end
  // A parabola through the best trial and its neighbours: its vertex is the rate, its curvature
  // the information. The summed squares are N S(rate) over N spheres (2N numbers less 6 per view's
  // pose); one standard error moves them by the residual variance per number.
  const double below = agreement[best - 1], at = agreement[best], above = agreement[best + 1];
  const double curvature = (below - 2 * at + above) / (2 * kStep * kStep);  // S'' / 2
  if (!(curvature > 0)) return m;
  m.rate = rates[best] - (above - below) / (4 * curvature * kStep);
  const double freedom = 2.0 * spheres - 6.0 * m.views;
  if (freedom <= 0) return m;
  const double least = at - curvature * (m.rate - rates[best]) * (m.rate - rates[best]);
  const double variance = least * spheres / freedom;
  m.sigma = std::sqrt(variance / (spheres * curvature));
  m.used = true;
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

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
  std::vector<double> rates;  // the trials, in increasing order
  std::vector<ViewResiduals> residuals;
  const auto try_rate = [&](double rate) {
    CalibrationOptions o = options;
    o.contrast_loss = rate;
    const auto at = static_cast<std::size_t>(std::lower_bound(rates.begin(), rates.end(), rate) - rates.begin());
    rates.insert(rates.begin() + static_cast<std::ptrdiff_t>(at), rate);
    residuals.insert(residuals.begin() + static_cast<std::ptrdiff_t>(at), residuals_by_view(calibrate_sample(o)));
  };
  ContrastLossMeasurement m;
  std::vector<double> agreement;
  std::vector<int> spheres;
  // Trials at 0 and one step, then a step beyond the last while it agrees better than the one
  // before (up to the range's end); when 0 agrees best, half a step between. The agreement is
  // judged on the views every trial calibrated.
  int highest = 1;  // the last trial's rate in steps
  const int most = static_cast<int>(std::floor(kMostContrastLoss / kStep + 1e-9));
  try_rate(0);
  try_rate(kStep);
  while (true) {
    std::vector<int> common;
    for (const auto& entry : residuals.front()) {
      const int v = entry.first;
      if (std::all_of(residuals.begin(), residuals.end(), [v](const ViewResiduals& r) { return r.contains(v); }))
        common.push_back(v);
    }
    agreement.assign(rates.size(), HUGE_VAL);
    spheres.assign(rates.size(), 0);
    for (std::size_t t = 0; t < rates.size(); ++t) {
      double sum = 0;
      for (int v : common) {
        sum += residuals[t].at(v).first;
        spheres[t] += residuals[t].at(v).second;
      }
      if (spheres[t] > 0) agreement[t] = sum / spheres[t];
    }
    m.views = static_cast<int>(common.size());
    const std::size_t last = rates.size() - 1;
    if (agreement[last] < agreement[last - 1] && highest < most)
      try_rate(++highest * kStep);
    else if (rates.size() == 2 && agreement[0] <= agreement[1])
      try_rate(kStep / 2);
    else
      break;
  }
  m.trial_rates = rates;
  m.mean_squared_px2 = agreement;
  m.sigma = HUGE_VAL;
  const auto best = static_cast<std::size_t>(std::min_element(agreement.begin(), agreement.end()) - agreement.begin());
  m.spheres = spheres[best];
  m.rate = rates[best];
  if (m.views == 0 || (best + 1 == rates.size() && highest >= most)) return m;  // nothing calibrated, or the range's end
  // A parabola through the best trial and its neighbours (the first three when 0 is best): its
  // vertex is the rate, its curvature the information. The summed squares are N S(rate) over N
  // spheres (2N numbers less 6 per view's pose); one standard error moves them by the residual
  // variance per number.
  const std::size_t mid = std::clamp<std::size_t>(best, 1, rates.size() - 2);
  const double x0 = rates[mid - 1], x1 = rates[mid], x2 = rates[mid + 1];
  const double y0 = agreement[mid - 1], y1 = agreement[mid], y2 = agreement[mid + 1];
  const double slope01 = (y1 - y0) / (x1 - x0), curvature = ((y2 - y1) / (x2 - x1) - slope01) / (x2 - x0);  // S'' / 2
  if (!(curvature > 0)) return m;
  const double vertex = 0.5 * (x0 + x1) - slope01 / (2 * curvature);
  if (vertex <= 0) {  // no loss: a contrast that grew with the background would stand for another model error
    m.rate = 0;
    return m;
  }
  m.rate = vertex;
  const double least = y0 + slope01 * (vertex - x0) + curvature * (vertex - x0) * (vertex - x1);
  const double freedom = 2.0 * m.spheres - 6.0 * m.views;
  if (freedom <= 0) return m;
  const double variance = least * m.spheres / freedom;
  m.sigma = std::sqrt(variance / (m.spheres * curvature));
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

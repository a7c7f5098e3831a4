#include "ctk/calib/holder_measurement.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <sstream>

#include "ctk/core/error.hpp"
#include "ctk/geom/holder_file.hpp"

namespace ctk {

namespace {

nlohmann::json xyz(const Eigen::Vector3d& v) { return {v.x(), v.y(), v.z()}; }

}  // namespace

void HolderMeasurementOptions::validate() const {
  diagnosis.validate();
  require_option(min_views >= 10, "HolderMeasurementOptions.min_views", "10 or more", min_views);
}

namespace {

// One pass: the scan's views matched to `scan`'s holder, the diagnosis, then every centre fitted
// with every view's pose and the effects the diagnosis put in the model.
struct CentresFit {
  DiagnosisRun diagnosis;
  std::vector<Effect> fitted_with;  // the diagnosis' effects, refitted beside the centres
  std::vector<Effect> active;       // those and sphere_positions, in fit order
  EffectParameters start;
  ScanModelFit fit;
};

CentresFit fit_centres(const ScanDescription& scan, const Geometry& geometry, const HolderMeasurementOptions& options,
                       bool with_covariance, const std::function<void(int, int)>& progress,
                       const std::function<void(const std::string&)>& log) {
  CentresFit c;
  c.diagnosis = run_diagnosis(scan, geometry, options.diagnosis, progress, log);
  const ScanObservations& o = c.diagnosis.observations;
  if (static_cast<int>(o.views.size()) < options.min_views)
    throw InputError(geometry.source(), "views",
                     std::to_string(o.views.size()) + " calibrated views; measuring a holder needs at least " +
                         std::to_string(options.min_views) + " from well-spread directions (a spherical or random trajectory)");
  const Diagnosis& d = c.diagnosis.diagnosis;
  for (Effect e : d.accepted)
    if (e != Effect::sphere_positions) c.fitted_with.push_back(e);
  for (const EffectFinding& f : d.outside) c.fitted_with.push_back(f.effect);
  c.active = c.fitted_with;
  c.active.push_back(Effect::sphere_positions);
  c.start = d.model;
  c.start.free_spheres.clear();  // every centre, the declared list's gauge
  std::vector<std::size_t> views(o.views.size());
  std::iota(views.begin(), views.end(), std::size_t{0});
  if (log)
    log("measuring " + std::to_string(o.setup.holder.spheres_mm.size()) + " sphere centres with " + std::to_string(views.size()) +
        " view poses ...");
  c.fit = fit_scan_model(o, c.active, views, c.start, with_covariance);
  return c;
}

}  // namespace

HolderMeasurement run_holder_measurement(const ScanDescription& scan, const Geometry& geometry,
                                         const HolderMeasurementOptions& options, const std::function<void(int, int)>& progress,
                                         const std::function<void(const std::string&)>& log) {
  options.validate();
  // Matched to the declared holder, a view drops the spheres whose error it sees largest as
  // outliers, and so the first pass underestimates the errors it measures; the second pass
  // matches every view to the first pass's holder, whose residuals are the detection noise.
  const CentresFit first = fit_centres(scan, geometry, options, false, progress, log);
  ScanDescription again = scan;
  for (std::size_t k = 0; k < again.holder->spheres_mm.size(); ++k)
    again.holder->spheres_mm[k] += first.fit.parameters.spheres[k];
  if (log) log("first pass done; matching the views to its centres again");
  CentresFit second = fit_centres(again, geometry, options, true, progress, log);
  const ScanObservations& o = second.diagnosis.observations;
  const ScanModelFit& fit = second.fit;

  HolderMeasurement m;
  m.fitted_with = second.fitted_with;
  m.declared = *scan.holder;
  m.measured = *again.holder;
  m.rms_px_declared = first.diagnosis.diagnosis.before_fit.image_rms_px();
  m.rms_px_measured = fit.image_rms_px();

  // Degrees of freedom: every image and prior residual, less the poses, the effects and the
  // centres (3 each, 7 fixed by the gauge). The detection noise was measured on the declared
  // holder's residuals, which carry the holder's own error; the joint fit's chi-square per
  // degree of freedom says what the noise really was.
  const std::size_t spheres = m.declared.spheres_mm.size();
  int residuals = 0;
  for (int r : fit.residual_count) residuals += r;
  int parameters = 3 * static_cast<int>(spheres) - 7;
  for (Effect e : m.fitted_with) parameters += parameter_count(e, o);
  const double chi2 = std::accumulate(fit.cost.begin(), fit.cost.end(), 0.0);
  const int dof = residuals - parameters;
  m.variance_factor = dof > 0 ? chi2 / dof : 1.0;

  // The same measurement from the even and the odd views: where their difference exceeds what
  // their covariances predict, the centres carry errors that are not the detection noise (a
  // centre's bias that changes with the direction it is seen from), and the stated uncertainty
  // grows by that factor.
  std::vector<std::size_t> halves[2];
  for (std::size_t i = 0; i < o.views.size(); ++i) halves[i % 2].push_back(i);
  const ScanModelFit even = fit_scan_model(o, second.active, halves[0], second.start, true);
  const ScanModelFit odd = fit_scan_model(o, second.active, halves[1], second.start, true);
  const auto slot = static_cast<std::size_t>(std::find(second.active.begin(), second.active.end(), Effect::sphere_positions) -
                                             second.active.begin());
  const auto variance = [&](const ScanModelFit& f, std::size_t k) {
    if (f.covariance.size() == 0) return Eigen::Vector3d(Eigen::Vector3d::Constant(std::nan("")));
    const auto at = static_cast<Eigen::Index>(f.covariance_offsets[slot] + 3 * static_cast<int>(k));
    return Eigen::Vector3d(m.variance_factor * f.covariance.block(at, at, 3, 3).diagonal().cwiseMax(0.0));
  };
  double z2 = 0;
  int compared = 0;
  for (std::size_t k = 0; k < spheres; ++k) {
    const Eigen::Vector3d difference = even.parameters.spheres[k] - odd.parameters.spheres[k];
    const Eigen::Vector3d predicted = variance(even, k) + variance(odd, k);
    for (int a = 0; a < 3; ++a)
      if (predicted[a] > 0 && std::isfinite(predicted[a])) {
        z2 += difference[a] * difference[a] / predicted[a];
        ++compared;
      }
  }
  m.halves_factor = compared > 0 ? std::sqrt(z2 / compared) : std::nan("");
  const double inflate = std::isfinite(m.halves_factor) ? std::max(1.0, m.halves_factor) : 1.0;

  m.views_per_sphere.assign(spheres, 0);
  for (const ViewObservations& v : o.views)
    for (int k : v.spheres) ++m.views_per_sphere[static_cast<std::size_t>(k)];
  for (std::size_t k = 0; k < spheres; ++k) {
    m.measured.spheres_mm[k] += fit.parameters.spheres[k];
    m.sigma_mm.push_back(inflate * variance(fit, k).cwiseSqrt());
  }
  m.helix = fit_helix(m.measured.spheres_mm, m.declared.helix);
  m.diagnosis = std::move(second.diagnosis);
  if (log) log(m.brief());
  return m;
}

nlohmann::json HolderMeasurement::holder_file(const std::string& scan_name) const {
  nlohmann::json j = holder_to_json(measured);
  j["format"] = "ctk-holder/1";
  j["name"] = "measured from " + scan_name;
  nlohmann::json sigma = nlohmann::json::array(), offsets = nlohmann::json::array(), deviation = nlohmann::json::array();
  for (std::size_t k = 0; k < measured.spheres_mm.size(); ++k) {
    sigma.push_back(xyz(sigma_mm[k]));
    offsets.push_back(xyz(measured.spheres_mm[k] - declared.spheres_mm[k]));
    deviation.push_back(xyz(helix.deviation_mm[k]));
  }
  nlohmann::json effects = nlohmann::json::array();
  for (Effect e : fitted_with) effects.push_back(effect_name(e));
  j["measurement"] = {{"scan", scan_name},
                      {"views", diagnosis.observations.views.size()},
                      {"fitted_with", effects},
                      {"gauge", "the declared centres' centroid, orientation and scale"},
                      {"image_rms_px", {{"declared", rms_px_declared}, {"measured", rms_px_measured}}},
                      {"variance_factor", variance_factor},
                      {"halves_factor", halves_factor},
                      {"spheres_sigma_mm", sigma},
                      {"offsets_mm", offsets},
                      {"views_per_sphere", views_per_sphere},
                      {"helix_fit",
                       {{"radius_mm", helix.helix.radius_mm},
                        {"rho_rad_per_mm", helix.helix.rho_rad_per_mm},
                        {"phase_rad", helix.helix.phase_rad},
                        {"axis_tilt_deg", {helix.axis_tilt_rad.x() * 180 / M_PI, helix.axis_tilt_rad.y() * 180 / M_PI}},
                        {"axis_offset_mm", {helix.axis_offset_mm.x(), helix.axis_offset_mm.y()}},
                        {"rms_deviation_mm", helix.rms_deviation_mm},
                        {"deviations_mm", deviation}}}};
  return j;
}

std::string HolderMeasurement::brief() const {
  double offset_sq = 0, sigma_sq = 0;
  for (std::size_t k = 0; k < measured.spheres_mm.size(); ++k) {
    offset_sq += (measured.spheres_mm[k] - declared.spheres_mm[k]).squaredNorm();
    sigma_sq += sigma_mm[k].squaredNorm();
  }
  const auto n = static_cast<double>(std::max<std::size_t>(1, measured.spheres_mm.size()));
  std::ostringstream b;
  b.precision(3);
  b << "holder measured: " << measured.spheres_mm.size() << " centres, " << std::sqrt(offset_sq / n)
    << " mm RMS from the declared (3-D), each to " << std::sqrt(sigma_sq / n) << " mm RMS (1 sigma, 3-D)\n"
    << "image RMS " << rms_px_declared << " -> " << rms_px_measured << " px per sphere; variance factor " << variance_factor
    << "; even and odd views differ " << halves_factor << " times what they state"
    << (halves_factor > 1 ? " (uncertainties scaled by it)" : "") << "\nhelix through the centres: radius "
    << helix.helix.radius_mm << " mm, pitch " << 2 * M_PI / helix.helix.rho_rad_per_mm << " mm, axis tilted "
    << helix.axis_tilt_rad.norm() * 180 / M_PI << " deg, centres " << helix.rms_deviation_mm << " mm RMS off it";
  return b.str();
}

}  // namespace ctk

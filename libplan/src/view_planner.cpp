#include "ctk/plan/view_planner.hpp"
#include "ctk/core/error.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace ctk {

namespace {
constexpr double kDegree = M_PI / 180.0;
}

void PlannerOptions::validate() const {
  require_option(candidate_nside >= 1, "PlannerOptions.candidate_nside", "a HEALPix nside of at least 1", candidate_nside);
  require_option(planned_views >= 1, "PlannerOptions.planned_views", "at least 1", planned_views);
  require_option(damage_exponent >= 0, "PlannerOptions.damage_exponent", "a number of 0 or more", damage_exponent);
  require_option(spread_exponent > 0, "PlannerOptions.spread_exponent", "a number above 0", spread_exponent);
  require_option(widest_gap_fraction >= 0 && widest_gap_fraction <= 1, "PlannerOptions.widest_gap_fraction", "a share in [0, 1]",
                 widest_gap_fraction);
  require_option(edge_tangency_weight >= 0 && edge_tangency_weight <= 1, "PlannerOptions.edge_tangency_weight",
                 "a share in [0, 1]", edge_tangency_weight);
  require_option(damage_floor_mm > 0, "PlannerOptions.damage_floor_mm", "a number above 0 (it divides)", damage_floor_mm);
  require_option(unreachable_radius_deg >= 0 && unreachable_radius_deg < 180, "PlannerOptions.unreachable_radius_deg",
                 "an angle in [0, 180) deg", unreachable_radius_deg);
}

ViewPlanner::ViewPlanner(const PlannerOptions& options)
    : options_((options.validate(), options)),
      candidates_(HealpixSphere(options.candidate_nside).directions()),
      rng_(options.seed) {}

void ViewPlanner::record_acquired(const Eigen::Vector3d& d) { acquired_.push_back(d.normalized()); }
void ViewPlanner::record_unreachable(const Eigen::Vector3d& d) { unreachable_.push_back(d.normalized()); }

void ViewPlanner::set_damage(const std::vector<double>& longest_path_mm) {
  if (!longest_path_mm.empty() && longest_path_mm.size() != candidates_.size())
    throw std::invalid_argument("set_damage: one value per candidate direction expected");
  damage_ = longest_path_mm;
}

void ViewPlanner::set_edge_demand(const std::vector<double>& relative_demand) {
  if (!relative_demand.empty() && relative_demand.size() != candidates_.size())
    throw std::invalid_argument("set_edge_demand: one value per candidate direction expected");
  edge_demand_ = relative_demand;
}

std::vector<CandidateWeight> ViewPlanner::weights() const {
  std::vector<CandidateWeight> w(candidates_.size());
  // Half the sphere's area shared among the planned views: their typical spacing.
  const double g0 = std::sqrt(2.0 * M_PI / std::max(1, options_.planned_views));
  const double cos_unreachable = std::cos(options_.unreachable_radius_deg * kDegree);
  double least = 1e300, widest = 0;
  std::vector<double> gap(candidates_.size(), 0.0);
  for (std::size_t c = 0; c < candidates_.size(); ++c) {
    const Eigen::Vector3d& d = candidates_[c];
    for (const Eigen::Vector3d& u : unreachable_)
      if (d.dot(u) >= cos_unreachable) w[c].reach = 0;
    // Where the edges want views more densely, the spacing they should have shrinks with the
    // square root of the density (views per area).
    if (!edge_demand_.empty())
      w[c].density = (1 - options_.edge_tangency_weight) + options_.edge_tangency_weight * edge_demand_[c];
    double nearest = 1e300;
    for (const Eigen::Vector3d& a : acquired_) nearest = std::min(nearest, line_distance_rad(d, a));
    const double spacings = nearest / g0 * std::sqrt(w[c].density);
    gap[c] = spacings;
    if (!acquired_.empty()) w[c].spread = std::pow(1.0 - std::exp(-spacings * spacings), options_.spread_exponent);
    if (w[c].reach > 0) widest = std::max(widest, spacings);
    if (!damage_.empty() && w[c].reach > 0) least = std::min(least, damage_[c] + options_.damage_floor_mm);
  }
  if (!acquired_.empty() && options_.widest_gap_fraction > 0)
    for (std::size_t c = 0; c < candidates_.size(); ++c)
      if (gap[c] < options_.widest_gap_fraction * widest) w[c].spread = 0;
  if (!damage_.empty())
    for (std::size_t c = 0; c < candidates_.size(); ++c)
      w[c].damage = std::pow(least / (damage_[c] + options_.damage_floor_mm), options_.damage_exponent);
  return w;
}

std::optional<Eigen::Vector3d> ViewPlanner::next() {
  const std::vector<CandidateWeight> w = weights();
  std::vector<double> p;
  double total = 0;
  for (const CandidateWeight& c : w) {
    p.push_back(c.weight());
    total += p.back();
  }
  if (!(total > 0)) return std::nullopt;
  std::discrete_distribution<std::size_t> draw(p.begin(), p.end());
  return candidates_[draw(rng_)];
}

}  // namespace ctk

#include "ctk/recon/held_out_fit.hpp"

#include <algorithm>
#include <cmath>
#include <string>

#include "ctk/recon/ordered_subsets.hpp"
#include "vector_ops.hpp"

namespace ctk {

std::vector<int> held_out_positions(const std::vector<ProjectionMatrix>& views, int every, const Eigen::Vector3d& centre_mm) {
  if (every <= 0 || static_cast<int>(views.size()) < every) return {};
  std::vector<int> chosen = ordered_subsets(views, every, centre_mm).front();
  std::sort(chosen.begin(), chosen.end());
  return chosen;
}

HeldOutFit::HeldOutFit(std::shared_ptr<const ProjectionOperator> A, ProjectionStack b, ProjectionStack w,
                       std::vector<int> view_indices, std::size_t pixels_per_view)
    : A_(std::move(A)),
      b_(std::move(b)),
      w_(std::move(w)),
      projected_(b_.views, b_.rows, b_.cols),
      previous_(b_.views, b_.rows, b_.cols),
      view_indices_(std::move(view_indices)),
      views_(view_indices_.empty() ? b_.views : static_cast<int>(view_indices_.size())),
      rays_(double(views_) * double(pixels_per_view > 0 ? pixels_per_view : b_.pixels_per_view())) {}

void HeldOutFit::observe(int iteration, const Volume& x) {
  A_->apply(x, projected_);
  static const FloatBuffer unit;
  const FloatBuffer& w = w_.views > 0 ? w_.data : unit;
  // The misfit, and the weighted square of what the projections moved since the last iterate.
  double misfit = 0, moved = 0;
  const std::ptrdiff_t n = static_cast<std::ptrdiff_t>(b_.data.size());
  const bool first = iterations_.empty();
#pragma omp parallel for reduction(+ : misfit, moved) schedule(static)
  for (std::ptrdiff_t i = 0; i < n; ++i) {
    const std::size_t k = static_cast<std::size_t>(i);
    const double wk = w.empty() ? 1.0 : double(w[k]);
    misfit += wk * std::pow(double(projected_.data[k]) - b_.data[k], 2);
    if (!first) moved += wk * std::pow(double(projected_.data[k]) - previous_.data[k], 2);
  }
  const double fit = 0.5 * A_->sum_over_range(misfit);
  moved = A_->sum_over_range(moved);
  std::swap(projected_, previous_);
  // The held-out data's noise n (variance c / w per ray) moves the change of the misfit by
  // sum w (A dx) n, of variance c sum w (A dx)^2; c is at most the misfit per ray of the best
  // iterate. An improvement within kHeldOutSignificance of that is not the image getting better.
  if (!first) {
    const double noise_per_ray = 2 * std::min(best_fit_, fit) / std::max(rays_, 1.0);
    significant_ = fits_.back() - fit > kHeldOutSignificance * std::sqrt(noise_per_ray * moved);
  }
  iterations_.push_back(iteration);
  fits_.push_back(fit);
  if (significant_) {
    best_iteration_ = iteration;
    best_fit_ = fit;
    best_ = x;
  }
}

StoppingRule HeldOutFit::rule() const {
  return [this]() -> std::optional<std::string> {
    if (significant_) return std::nullopt;
    return "the fit of " + std::to_string(views_) + " held-out views stopped improving beyond their noise after iteration " +
           std::to_string(best_iteration_) + " (its iterate is the result)";
  };
}

int HeldOutFit::restore_best(Volume& x) {
  if (best_iteration_ >= 0 && best_iteration_ != iterations_.back()) std::swap(x, best_);
  best_ = Volume();
  return best_iteration_;
}

nlohmann::json HeldOutFit::report() const {
  nlohmann::json r = {{"views", views_}, {"iterations", iterations_}, {"fit", fits_}, {"best_iteration", best_iteration_}};
  if (!view_indices_.empty()) r["view_indices"] = view_indices_;
  return r;
}

}  // namespace ctk

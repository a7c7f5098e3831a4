#include "ctk/recon/held_out_fit.hpp"

#include <algorithm>
#include <cmath>
#include <string>

#include "ctk/recon/ordered_subsets.hpp"
#include "vector_ops.hpp"

namespace ctk {

namespace {

// Only iterates past the first go back or into a mean: the start is no image of the data, and the
// first epoch from it a blurred one still far from them (on the standard cases 1.3 to 1.6 times
// the second's RMSE).
constexpr int kFirstUsableBefore = 2;

}  // namespace

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
    if (result_ != HeldOutResult::last_improving && best_iteration_ >= 0) {
      before_best_iteration_ = best_iteration_;
      std::swap(before_best_, best_);
    }
    best_iteration_ = iteration;
    best_fit_ = fit;
    best_ = x;
  }
}

HeldOutResult held_out_result(ReconstructionMethod method) {
  return method == ReconstructionMethod::os_sqs ? HeldOutResult::one_before : HeldOutResult::last_improving;
}

int held_out_volumes(HeldOutResult which) { return which == HeldOutResult::last_improving ? 1 : 2; }

void HeldOutFit::return_result(HeldOutResult which) { result_ = which; }

std::vector<int> HeldOutFit::result_iterations() const {
  if (result_ == HeldOutResult::last_improving || before_best_iteration_ < kFirstUsableBefore) return {best_iteration_};
  if (result_ == HeldOutResult::one_before) return {before_best_iteration_};
  return {before_best_iteration_, best_iteration_};
}

StoppingRule HeldOutFit::rule() const {
  return [this]() -> std::optional<std::string> {
    if (significant_) return std::nullopt;
    const std::vector<int> result = result_iterations();
    return "the fit of " + std::to_string(views_) + " held-out views stopped improving beyond their noise after iteration " +
           std::to_string(best_iteration_) +
           (result.size() == 2 ? " (the mean of its iterate and the one before is the result)"
            : result.front() != best_iteration_
                ? " (the iterate of " + std::to_string(result.front()) + ", the improving one before it, is the result)"
                : " (its iterate is the result)");
  };
}

int HeldOutFit::restore_best(Volume& x) {
  const std::vector<int> result = result_iterations();
  if (result.size() == 2) {
    const std::ptrdiff_t n = static_cast<std::ptrdiff_t>(x.data.size());
#pragma omp parallel for schedule(static)
    for (std::ptrdiff_t i = 0; i < n; ++i) {
      const auto k = static_cast<std::size_t>(i);
      x.data[k] = 0.5f * (best_.data[k] + before_best_.data[k]);
    }
  } else if (result.front() != best_iteration_) {  // the improving iterate before the last
    std::swap(x, before_best_);
  } else if (best_iteration_ >= 0 && best_iteration_ != iterations_.back()) {
    std::swap(x, best_);
  }
  best_ = Volume();
  before_best_ = Volume();
  return best_iteration_;
}

nlohmann::json HeldOutFit::report() const {
  nlohmann::json r = {{"views", views_}, {"iterations", iterations_}, {"fit", fits_}, {"best_iteration", best_iteration_}};
  r["result_iterations"] = result_iterations();
  if (!view_indices_.empty()) r["view_indices"] = view_indices_;
  return r;
}

}  // namespace ctk

#include "ctk/plan/incremental_reconstruction.hpp"

#include <algorithm>
#include <stdexcept>
#include <utility>

#include "ctk/core/error.hpp"
#include "ctk/geom/detector_binning.hpp"
#include "ctk/proj/joseph_operator.hpp"

namespace ctk {

namespace {

void append_view(ProjectionStack& stack, const Image& image) {
  stack.views += 1;
  stack.rows = image.rows;
  stack.cols = image.cols;
  stack.data.insert(stack.data.end(), image.pixels.begin(), image.pixels.end());
}

}  // namespace

void IncrementalOptions::validate() const {
  require_option(binning >= 1, "IncrementalOptions.binning", "at least 1 (detector pixels per coarse pixel)", binning);
  require_option(first_update_iterations >= 1, "IncrementalOptions.first_update_iterations", "at least 1",
                 first_update_iterations);
  require_option(iterations_per_update >= 1, "IncrementalOptions.iterations_per_update", "at least 1", iterations_per_update);
  require_option(lambda >= 0, "IncrementalOptions.lambda", "a number of 0 or more", lambda);
}

IncrementalReconstruction::IncrementalReconstruction(const VolumeLayout& layout, const Detector& detector,
                                                     const IncrementalOptions& options)
    : options_((options.validate(), options)),
      detector_(detector),
      coarse_(binned_detector(detector, options.binning)),
      x_(layout) {}

void IncrementalReconstruction::add_view(const ProjectionMatrix& P, const Image& line_integrals, const Image& weights) {
  if (line_integrals.cols != detector_.cols || line_integrals.rows != detector_.rows)
    throw std::invalid_argument("add_view: the image is not the detector's size");
  matrices_.push_back(binned_matrix(P, options_.binning));
  append_view(b_, binned_image(line_integrals, options_.binning));
  const Image w =
      weights.pixels.empty()
          ? Image{coarse_.cols, coarse_.rows,
                  std::vector<float>(static_cast<std::size_t>(coarse_.cols) * static_cast<std::size_t>(coarse_.rows), 1.0f)}
          : binned_image(weights, options_.binning);
  append_view(w_, w);
  // The residual A x - b of the new view: its forward projection through the current volume (none
  // is needed before the first update, when the volume is still zero).
  ProjectionStack predicted(1, coarse_.rows, coarse_.cols);
  if (updates_ > 0) projector_.forward(x_, {matrices_.back()}, predicted);
  const float* b = b_.view(b_.views - 1);
  for (std::size_t i = 0; i < predicted.data.size(); ++i) predicted.data[i] -= b[i];
  append_view(residual_, Image{coarse_.cols, coarse_.rows, std::vector<float>(predicted.data.begin(), predicted.data.end())});
}

SolverReport IncrementalReconstruction::update() {
  if (matrices_.empty()) return {};
  WlsOptions o;
  o.iterations = updates_++ == 0 ? options_.first_update_iterations : options_.iterations_per_update;
  o.tolerance = 0;
  o.lambda = options_.lambda;
  o.regulariser = Regulariser::gradient;
  o.gradient_after_last = false;
  return solve_wls_cg(JosephOperator(matrices_, x_.layout, coarse_.rows, coarse_.cols), b_, &w_, x_, residual_, o);
}

}  // namespace ctk

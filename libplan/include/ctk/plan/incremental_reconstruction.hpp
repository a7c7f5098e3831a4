#pragma once
// The planner's running picture of the sample: a coarse volume that grows with every view.
// Each new view is binned onto a coarse detector and appended; the volume is then improved by a
// few weighted-least-squares CG iterations started from the previous volume (warm start): the
// first update (after the scout) solves properly, each later one takes one more step, so a
// planning step costs one forward and one back projection of the views so far, not a full solve.
// The residual A x - b is kept between updates (each step updates it alongside x), so only a new
// view needs projecting through the volume to start the next step.
#include <vector>

#include "ctk/core/image_io.hpp"
#include "ctk/proj/joseph_projector.hpp"
#include "ctk/recon/wls_cg.hpp"

namespace ctk {

struct IncrementalOptions {
  int binning = 3;  // detector pixels per coarse pixel, per axis
  int first_update_iterations = 8;
  int iterations_per_update = 1;
  double lambda = 0.02;   // gradient penalty (voxel units) against streaks from few views
  void validate() const;  // std::invalid_argument naming the field
};

class IncrementalReconstruction {
 public:
  IncrementalReconstruction(const VolumeLayout& layout, const Detector& detector, const IncrementalOptions& options = {});

  /// `line_integrals` and `weights` at full detector resolution (weights may be empty: unit).
  void add_view(const ProjectionMatrix& P, const Image& line_integrals, const Image& weights);
  /// A few warm-started CG iterations over every view so far.
  SolverReport update();

  const Volume& volume() const { return x_; }
  int views() const { return static_cast<int>(matrices_.size()); }
  const Detector& coarse_detector() const { return coarse_; }

 private:
  IncrementalOptions options_;
  Detector detector_, coarse_;
  JosephProjector projector_;
  std::vector<ProjectionMatrix> matrices_;
  ProjectionStack b_, w_, residual_;  // residual_ = A x_ - b_, kept up to date
  Volume x_;
  int updates_ = 0;
};

}  // namespace ctk

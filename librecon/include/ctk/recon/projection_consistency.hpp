#pragma once
// The markerless yardstick: how well a reconstruction from some views predicts the views it
// never saw. Views are split by interleaving: the even views are reconstructed (FDK on a coarse
// grid), views 1 mod 4 are where effects are fitted, views 3 mod 4 where they are judged. A model
// closer to the physics predicts the held-out views better; a wrong one leaves structured residuals.
#include <vector>

#include "ctk/core/projection_stack.hpp"
#include "ctk/core/volume.hpp"
#include "ctk/geom/detector.hpp"
#include "ctk/recon/global_geometry.hpp"

namespace ctk {

struct ConsistencySplit {
  std::vector<int> reconstruct, fit, judge;  // indices into the stack
};
/// Even views reconstruct; 1 mod 4 fit; 3 mod 4 judge.
ConsistencySplit interleaved_split(int views);

/// The acquisition physics the forward model can include.
struct ForwardModel {
  double blur_arc_rad = 0;  // angular_blur: each view integrates this arc of continuous rotation
  int blur_samples = 4;
  double hardening_c2 = 0;  // beam_hardening: straight line integral = p + c2 p^2 (p as measured)
  /// Not physics but the yardstick's own resolution: this fraction of a 3 x 3 box filter is mixed
  /// into every prediction, so that effects cannot win by merely smoothing a streaky prediction.
  double prediction_smoothing = 0;
  /// pixel_gain / column_gain: what each detector pixel adds to every view's line integral (its
  /// gain differs between the flat and the projections; a defective column), subtracted from the
  /// measurements before anything else. One value per pixel, row-major; empty: none.
  std::vector<float> pixel_offset;
};
/// Measured line integral p to the straight (monochromatic) one, and back.
double linearise_line_integral(double p, double c2);
double measured_from_linear(double y, double c2);

class ConsistencyProbe {
 public:
  /// `b`: measured line integrals of every view (kept by reference: it must outlive the probe),
  /// `nominal` their matrices (a circular orbit), `layout` the (coarse) grid the held-out
  /// prediction is reconstructed on.
  ConsistencyProbe(const ProjectionStack& b, std::vector<ProjectionMatrix> nominal, const Detector& detector,
                   const VolumeLayout& layout, ConsistencySplit split);

  /// Mean squared residual per fit (or judge) view, in measured line-integral units squared, over
  /// the detector rows except a tenth at the top and at the bottom (a long object's incomplete
  /// region): the views not named are not predicted. `fit_residuals` / `judge_residuals`
  /// (optional) receive predicted - measured for those views (0 in the rows left out).
  std::vector<double> fit_costs(const GlobalGeometry& geometry, const ForwardModel& model,
                                ProjectionStack* fit_residuals = nullptr) const;
  std::vector<double> judge_costs(const GlobalGeometry& geometry, const ForwardModel& model,
                                  ProjectionStack* judge_residuals = nullptr) const;
  /// FDK from every view with the model's geometry and linearisation, on `layout`.
  Volume reconstruct_all(const GlobalGeometry& geometry, const ForwardModel& model, const VolumeLayout& layout) const;
  const CircularTrajectory& orbit() const { return orbit_; }
  const Detector& detector() const { return detector_; }
  const ConsistencySplit& split() const { return split_; }
  const ProjectionStack& measured() const { return b_; }
  /// Detector rows left out of the costs at the top and at the bottom.
  int row_margin() const { return row_margin_; }
  /// Principal point of the first nominal view (the detector offsets are relative to it).
  Eigen::Vector2d nominal_principal_point() const;

 private:
  Volume reconstruct(const std::vector<int>& views, const std::vector<ProjectionMatrix>& matrices, const ForwardModel& model,
                     const VolumeLayout& layout) const;
  std::vector<double> costs(const std::vector<int>& held_out, const GlobalGeometry& geometry, const ForwardModel& model,
                            ProjectionStack* residuals) const;

  const ProjectionStack& b_;
  std::vector<ProjectionMatrix> nominal_;
  Detector detector_;
  VolumeLayout layout_;
  ConsistencySplit split_;
  CircularTrajectory orbit_;
  int row_margin_;  // detector rows left out of the cost at the top and at the bottom
};

/// Edge sharpness of a volume, as line profiles show it: the mean of the largest 1 % of absolute
/// differences between neighbouring voxels along x and y in the central axial slice, per mm.
double edge_sharpness(const Volume& x);

}  // namespace ctk

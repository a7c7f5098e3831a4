#include "ctk/recon/projection_consistency.hpp"

#include <algorithm>
#include <cmath>
#include <utility>

#include "ctk/proj/arc_averaged_projection.hpp"

namespace ctk {

namespace {

// image <- (1 - a) image + a box3(image), the box clipped at the detector's edges.
void smooth_box3(std::vector<double>& image, int rows, int cols, double a) {
  const std::vector<double> in = image;
  for (int r = 0; r < rows; ++r)
    for (int c = 0; c < cols; ++c) {
      double s = 0;
      int n = 0;
      for (int dr = -1; dr <= 1; ++dr)
        for (int dc = -1; dc <= 1; ++dc) {
          const int rr = r + dr, cc = c + dc;
          if (rr < 0 || cc < 0 || rr >= rows || cc >= cols) continue;
          s += in[static_cast<std::size_t>(rr) * static_cast<std::size_t>(cols) + static_cast<std::size_t>(cc)];
          ++n;
        }
      double& x = image[static_cast<std::size_t>(r) * static_cast<std::size_t>(cols) + static_cast<std::size_t>(c)];
      x = (1 - a) * x + a * s / n;
    }
}

}  // namespace

ConsistencySplit interleaved_split(int views) {
  ConsistencySplit s;
  for (int k = 0; k < views; ++k) (k % 2 == 0 ? s.reconstruct : k % 4 == 1 ? s.fit : s.judge).push_back(k);
  return s;
}

double linearise_line_integral(double p, double c2) { return p + c2 * p * p; }

double measured_from_linear(double y, double c2) {
  if (c2 == 0) return y;
  // The root of c2 p^2 + p - y = 0 that tends to y as c2 -> 0 (stable form).
  const double disc = std::max(1.0 + 4.0 * c2 * y, 0.0);
  return 2.0 * y / (1.0 + std::sqrt(disc));
}

ConsistencyProbe::ConsistencyProbe(const ProjectionStack& b, std::vector<ProjectionMatrix> nominal, const Detector& detector,
                                   const VolumeLayout& layout, ConsistencySplit split)
    : b_(b),
      nominal_(std::move(nominal)),
      detector_(detector),
      layout_(layout),
      split_(std::move(split)),
      orbit_(fit_circular_trajectory(nominal_)),
      row_margin_(b.rows / 10) {}

Volume ConsistencyProbe::reconstruct(const std::vector<int>& views, const std::vector<ProjectionMatrix>& matrices,
                                     const ForwardModel& model, const VolumeLayout& layout) const {
  ProjectionStack sub(static_cast<int>(views.size()), b_.rows, b_.cols);
  std::vector<ProjectionMatrix> P;
  for (std::size_t i = 0; i < views.size(); ++i) {
    const float* in = b_.view(views[i]);
    float* out = sub.view(static_cast<int>(i));
    const float* offset = model.pixel_offset.empty() ? nullptr : model.pixel_offset.data();
    for (std::size_t p = 0; p < b_.pixels_per_view(); ++p)
      out[p] = static_cast<float>(linearise_line_integral(offset ? in[p] - offset[p] : in[p], model.hardening_c2));
    P.push_back(matrices[static_cast<std::size_t>(views[i])]);
  }
  Volume x(layout);
  fdk_reconstruct(P, sub, detector_, x);
  return x;
}

std::vector<double> ConsistencyProbe::fit_costs(const GlobalGeometry& geometry, const ForwardModel& model,
                                                ProjectionStack* fit_residuals) const {
  return costs(split_.fit, geometry, model, fit_residuals);
}

std::vector<double> ConsistencyProbe::judge_costs(const GlobalGeometry& geometry, const ForwardModel& model,
                                                  ProjectionStack* judge_residuals) const {
  return costs(split_.judge, geometry, model, judge_residuals);
}

std::vector<double> ConsistencyProbe::costs(const std::vector<int>& held_out, const GlobalGeometry& geometry,
                                            const ForwardModel& model, ProjectionStack* residuals) const {
  const std::vector<ProjectionMatrix> matrices = apply_global_geometry(geometry, nominal_, orbit_);
  const Volume x = reconstruct(split_.reconstruct, matrices, model, layout_);

  // Predict the held-out views (the mean over sub-views when the view integrates an arc).
  const int samples = model.blur_arc_rad > 0 ? std::max(model.blur_samples, 1) : 1;
  std::vector<std::vector<ProjectionMatrix>> sub_views;
  for (int v : held_out) {
    const ProjectionMatrix& P = matrices[static_cast<std::size_t>(v)];
    sub_views.push_back(samples == 1 ? std::vector<ProjectionMatrix>{P}
                                     : angular_sub_views(P, orbit_, model.blur_arc_rad, samples));
  }
  ProjectionStack y;
  ArcAveragedProjection(std::move(sub_views), layout_, b_.rows, b_.cols).apply(x, y);

  std::vector<double> c;
  if (residuals) *residuals = ProjectionStack(static_cast<int>(held_out.size()), b_.rows, b_.cols);
  for (std::size_t i = 0; i < held_out.size(); ++i) {
    const float* measured = b_.view(held_out[i]);
    float* residual = residuals ? residuals->view(static_cast<int>(i)) : nullptr;
    const float* view = y.view(static_cast<int>(i));
    std::vector<double> predicted(view, view + b_.pixels_per_view());
    if (model.prediction_smoothing > 0) smooth_box3(predicted, b_.rows, b_.cols, model.prediction_smoothing);
    // Rows near the top and bottom see parts of a long object that the other views miss (the
    // cone's incomplete region): no geometry predicts them, so they are left out of the cost.
    double sum = 0;
    const std::size_t first = static_cast<std::size_t>(row_margin_) * static_cast<std::size_t>(b_.cols);
    const std::size_t last = predicted.size() - first;
    const float* offset = model.pixel_offset.empty() ? nullptr : model.pixel_offset.data();
    for (std::size_t p = first; p < last; ++p) {
      const double r = measured_from_linear(predicted[p], model.hardening_c2) - (offset ? measured[p] - offset[p] : measured[p]);
      if (residual) residual[p] = static_cast<float>(r);
      sum += r * r;
    }
    c.push_back(sum / static_cast<double>(last - first));
  }
  return c;
}

Eigen::Vector2d ConsistencyProbe::nominal_principal_point() const {
  const auto K = nominal_.front().decompose().intrinsics;
  return {K.u0_px, K.v0_px};
}

Volume ConsistencyProbe::reconstruct_all(const GlobalGeometry& geometry, const ForwardModel& model,
                                         const VolumeLayout& layout) const {
  std::vector<int> all(static_cast<std::size_t>(b_.views));
  for (int k = 0; k < b_.views; ++k) all[static_cast<std::size_t>(k)] = k;
  return reconstruct(all, apply_global_geometry(geometry, nominal_, orbit_), model, layout);
}

double edge_sharpness(const Volume& x) {
  const auto& n = x.layout.size;
  const int k = n[2] / 2;
  std::vector<float> d;
  for (int j = 0; j < n[1]; ++j)
    for (int i = 0; i + 1 < n[0]; ++i)
      d.push_back(std::abs(x.at(i + 1, j, k) - x.at(i, j, k)) / static_cast<float>(x.layout.voxel_mm.x()));
  for (int j = 0; j + 1 < n[1]; ++j)
    for (int i = 0; i < n[0]; ++i)
      d.push_back(std::abs(x.at(i, j + 1, k) - x.at(i, j, k)) / static_cast<float>(x.layout.voxel_mm.y()));
  if (d.empty()) return 0;
  const std::size_t top = std::max<std::size_t>(1, d.size() / 100);
  std::nth_element(d.begin(), d.begin() + static_cast<std::ptrdiff_t>(top), d.end(), std::greater<>());
  double sum = 0;
  for (std::size_t i = 0; i < top; ++i) sum += d[i];
  return sum / static_cast<double>(top);
}

}  // namespace ctk

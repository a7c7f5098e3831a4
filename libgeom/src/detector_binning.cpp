#include "ctk/geom/detector_binning.hpp"

#include <stdexcept>
#include <string>

namespace ctk {

Detector binned_detector(const Detector& d, int b) {
  if (b < 1 || b > d.cols || b > d.rows)
    throw std::invalid_argument("binning factor " + std::to_string(b) + " does not fit a " + std::to_string(d.cols) + " x " +
                                std::to_string(d.rows) + " detector");
  return {d.cols / b, d.rows / b, d.pitch_u_mm * b, d.pitch_v_mm * b};
}

ProjectionMatrix binned_matrix(const ProjectionMatrix& P, int b) {
  // u' = (u - (b - 1) / 2) / b, likewise v'.
  Eigen::Matrix3d S = Eigen::Matrix3d::Identity();
  S(0, 0) = S(1, 1) = 1.0 / b;
  S(0, 2) = S(1, 2) = -0.5 * (b - 1) / b;
  return ProjectionMatrix(Matrix34d(S * P.matrix()));
}

Eigen::Vector2d binned_pixel(const Eigen::Vector2d& fine, int b) { return (fine.array() - 0.5 * (b - 1)) / b; }

Eigen::Vector2d unbinned_pixel(const Eigen::Vector2d& binned, int b) { return binned.array() * b + 0.5 * (b - 1); }

// The shift k1 r^2 (x - c) in fine pixels is b times smaller in binned ones, whose radius is b
// times smaller too: k1' = k1 b^2.
RadialDistortion binned_distortion(const RadialDistortion& d, int b) {
  return {d.k1_per_px2 * b * b, binned_pixel(d.centre_px, b)};
}

RadialDistortion unbinned_distortion(const RadialDistortion& d, int b) {
  return {d.k1_per_px2 / (b * b), unbinned_pixel(d.centre_px, b)};
}

Geometry binned_geometry(const Geometry& g, int b) {
  Geometry out = g;
  out.detector = binned_detector(g.detector, b);
  for (GeometryView& v : out.views)
    if (v.P) v.P = binned_matrix(*v.P, b);
  return out;
}

}  // namespace ctk

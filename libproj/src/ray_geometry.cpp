#include "ctk/proj/ray_geometry.hpp"

#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace ctk {

ViewRays view_rays(const ProjectionMatrix& P, const VolumeLayout& layout) {
  const Eigen::Matrix3d Minv = P.matrix().leftCols<3>().inverse();
  // Directions with positive depth: m3 . (Minv (u, v, 1)) = 1 > 0 for a normalised P.
  const Eigen::Vector3d inv_voxel = layout.voxel_mm.cwiseInverse();
  ViewRays r;
  r.source = (P.source_position() - layout.origin_mm).cwiseProduct(inv_voxel);
  r.d0 = Minv.col(2).cwiseProduct(inv_voxel);
  r.du = Minv.col(0).cwiseProduct(inv_voxel);
  r.dv = Minv.col(1).cwiseProduct(inv_voxel);
  return r;
}

namespace {
// k range where lo < p_mid + (k - k_mid) beta < hi, widened by one slice (the samples check).
void clip(double p_mid, double beta, double lo, double hi, double k_mid, double& k_lo, double& k_hi) {
  if (beta == 0) {
    if (!(p_mid > lo && p_mid < hi)) k_lo = std::numeric_limits<double>::infinity();
    return;
  }
  double a = k_mid + (lo - p_mid) / beta, b = k_mid + (hi - p_mid) / beta;
  if (a > b) std::swap(a, b);
  k_lo = std::max(k_lo, std::floor(a));
  k_hi = std::min(k_hi, std::ceil(b));
}
}  // namespace

MarchedRay march_ray(const ViewRays& rays, const VolumeLayout& layout, double u, double v) {
  const Eigen::Vector3d d = rays.d0 + u * rays.du + v * rays.dv;
  MarchedRay m;
  d.cwiseAbs().maxCoeff(&m.axis);
  const int a = m.axis;
  const auto [b, c] = other_axes(a);
  const double k_mid = 0.5 * (layout.size[static_cast<std::size_t>(a)] - 1);
  m.beta_b = d[b] / d[a];
  m.beta_c = d[c] / d[a];
  m.pb_mid = rays.source[b] + (k_mid - rays.source[a]) * m.beta_b;
  m.pc_mid = rays.source[c] + (k_mid - rays.source[a]) * m.beta_c;
  m.weight_mm = d.cwiseProduct(layout.voxel_mm).norm() / std::abs(d[a]);

  double k_lo = 0, k_hi = layout.size[static_cast<std::size_t>(a)] - 1;
  clip(m.pb_mid, m.beta_b, -1.0, layout.size[static_cast<std::size_t>(b)], k_mid, k_lo, k_hi);
  clip(m.pc_mid, m.beta_c, -1.0, layout.size[static_cast<std::size_t>(c)], k_mid, k_lo, k_hi);
  // Only points in front of the source: t = (k - s_a) / d_a > 0.
  if (d[a] > 0)
    k_lo = std::max(k_lo, std::floor(rays.source[a]) + 1);
  else
    k_hi = std::min(k_hi, std::ceil(rays.source[a]) - 1);
  if (k_lo <= k_hi) {
    m.k_first = static_cast<int>(k_lo);
    m.k_last = static_cast<int>(k_hi);
  }
  return m;
}

void check_stack_matches_views(int stack_views, int rows, int cols, std::size_t view_count) {
  if (stack_views != static_cast<int>(view_count))
    throw std::invalid_argument("projector: the stack has " + std::to_string(stack_views) + " views but " +
                                std::to_string(view_count) + " matrices were given");
  if (rows <= 0 || cols <= 0) throw std::invalid_argument("projector: empty detector");
}

}  // namespace ctk

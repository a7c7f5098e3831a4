#include "ray_table.hpp"

#include <Eigen/QR>
#include <algorithm>

namespace ctk::detail {

LanePath LanePath::for_view(const ViewRays& rays, const VolumeLayout& layout, int cols, int rows) {
  // At the central ray, the sample's c in a slice is c = s_c + (k - s_a) d_c / d_a; a pixel step
  // (du, dv) changes d_c / d_a in proportion to g = (du_c d_a - d_c du_a, dv_c d_a - d_c dv_a).
  // Lanes step across g.
  const double uc = 0.5 * (cols - 1), vc = 0.5 * (rows - 1);
  const Eigen::Vector3d d = rays.d0 + uc * rays.du + vc * rays.dv;
  int a = 0;
  d.cwiseAbs().maxCoeff(&a);  // the central ray's dominant axis, as march_ray finds it
  const int c = other_axes(a)[1];
  const double gu = rays.du[c] * d[a] - d[c] * rays.du[a], gv = rays.dv[c] * d[a] - d[c] * rays.dv[a];
  LanePath p;
  p.central_ray = d;
  p.axis = a;
  p.along_u = std::abs(gv) >= std::abs(gu);  // the step (gv, -gu) is mostly along u
  p.slope = p.along_u ? (gv != 0 ? -gu / gv : 0.0) : -gv / gu;
  p.minors = p.along_u ? rows : cols;
  p.find_footprint(rays, layout);
  // Lines only over the footprint's pixels (all of them when it is unbounded).
  const double major_lo = p.along_u ? p.u_lo : p.v_lo, major_hi = p.along_u ? p.u_hi : p.v_hi;
  const double minor_lo = p.along_u ? p.v_lo : p.u_lo, minor_hi = p.along_u ? p.v_hi : p.u_hi;
  const int major_count = p.along_u ? cols : rows;
  p.major_first = static_cast<int>(std::clamp(std::ceil(major_lo), 0.0, static_cast<double>(major_count)));
  const int major_last = static_cast<int>(std::clamp(std::floor(major_hi), -1.0, major_count - 1.0));
  const int minor_first = static_cast<int>(std::clamp(std::ceil(minor_lo), 0.0, static_cast<double>(p.minors)));
  const int minor_last = static_cast<int>(std::clamp(std::floor(minor_hi), -1.0, p.minors - 1.0));
  p.majors = std::max(0, major_last - p.major_first + 1);
  p.whole_detector = p.major_first == 0 && major_last == major_count - 1 && minor_first == 0 && minor_last == p.minors - 1;
  if (p.majors == 0 || minor_last < minor_first) {
    p.majors = 0, p.lines = 0;
    return p;
  }
  // Line j covers minors line_first + j + round(m slope) over the footprint's majors m.
  const int e0 = static_cast<int>(std::floor(p.major_first * p.slope + 0.5));
  const int e1 = static_cast<int>(std::floor(major_last * p.slope + 0.5));
  p.line_first = minor_first - std::max(e0, e1);
  p.lines = minor_last - minor_first + 1 + std::abs(e1 - e0);
  return p;
}

void LanePath::find_footprint(const ViewRays& rays, const VolumeLayout& layout) {
  // Pixel (u, v) of corner X solves d0 + u du + v dv = lambda (X - source). Every pixel's d has
  // the same depth (P is normalised), so depth(X) = n . (X - source) with n normal to du and dv
  // and n . d0 = 1, and lambda = 1 / depth(X).
  const Eigen::Vector3d normal = rays.du.cross(rays.dv) / rays.du.cross(rays.dv).dot(rays.d0);
  Eigen::Matrix3d A;
  A.col(0) = rays.du;
  A.col(1) = rays.dv;
  const Eigen::Vector3d box_lo = Eigen::Vector3d::Constant(-1.0);
  const Eigen::Vector3d box_hi(layout.size[0], layout.size[1], layout.size[2]);
  double lo_u = 1e300, hi_u = -1e300, lo_v = 1e300, hi_v = -1e300;
  for (int corner = 0; corner < 8; ++corner) {
    Eigen::Vector3d X;
    for (int i = 0; i < 3; ++i) X[i] = (corner >> i) & 1 ? box_hi[i] : box_lo[i];
    const double depth = normal.dot(X - rays.source);
    if (!(depth > 1e-6 * (X - rays.source).norm())) return;  // a corner behind the source or beside it: unbounded
    A.col(2) = -(X - rays.source);
    const Eigen::Vector3d uvl = A.colPivHouseholderQr().solve(-rays.d0);
    lo_u = std::min(lo_u, uvl.x()), hi_u = std::max(hi_u, uvl.x());
    lo_v = std::min(lo_v, uvl.y()), hi_v = std::max(hi_v, uvl.y());
  }
  // Half a pixel more for rounding: skipping a ray that touches would be an error, preparing one
  // that misses only costs time.
  u_lo = lo_u - 0.5, u_hi = hi_u + 0.5, v_lo = lo_v - 0.5, v_hi = hi_v + 0.5;
}

bool LanePath::meets_detector(int line, int lane, int count) const {
  int u0, v0, u1, v1;
  pixel(line, lane, u0, v0);
  pixel(line, lane + count - 1, u1, v1);
  if (std::max(u0, u1) < u_lo || std::min(u0, u1) > u_hi || std::max(v0, v1) < v_lo || std::min(v0, v1) > v_hi) return false;
  for (int l = lane; l < lane + count; ++l)
    if (inside(line, l)) return true;
  return false;
}

void RayTable::shape(int view_count, int row_count, int lanes) {
  views = view_count;
  rows = row_count;
  row_stride = (lanes + kMaxLanes - 1) / kMaxLanes * kMaxLanes;
  view_stride = rows * row_stride;
  slot_rows.assign(static_cast<std::size_t>(views), rows);
  const auto n = static_cast<std::size_t>(views) * static_cast<std::size_t>(view_stride);
  for (auto* v : {&pb_mid, &beta_b, &pc_mid, &beta_c, &weight, &k_mid, &value}) v->assign(n, 0.0f);
  for (auto* v : {&k_first, &k_last, &axis, &stride_a, &stride_b, &stride_c, &n_b, &n_c, &in_first, &in_last}) v->assign(n, 0);
  empty(0, n);
}

void RayTable::fill(const ViewRays& rays, const VolumeLayout& layout, int slot, const LanePath& path, int line_begin,
                    int ray_begin, int ray_end) {
  double u[kMaxLanes], v[kMaxLanes];
  PreparedRays p;
  // A run of entries at a time: the rest of a bundle (kMaxLanes lanes of one line) within the range.
  for (int r = ray_begin; r < ray_end;) {
    const int row = r / row_stride, lane = r % row_stride, bundle_lane = lane - lane % kMaxLanes;
    const int count = std::min(ray_end, row * row_stride + bundle_lane + kMaxLanes) - r;
    const std::size_t first = entry(slot, row, lane);
    r += count;
    if (!path.meets_detector(line_begin + row, bundle_lane, kMaxLanes)) {
      empty(first, first + static_cast<std::size_t>(count));
      continue;
    }
    lane_pixels(path, line_begin + row, lane, count, u, v);
    prepare_rays(rays, layout, origin_b, origin_c, u, v, count, p);
    store_rays(p, layout, count, *this, first);
  }
}

void RayTable::empty(std::size_t begin, std::size_t end) {
  // Array by array: one loop over all of them is not vectorised (the float arrays might alias).
  const auto set = [&](auto& array, auto to) {
    std::fill(array.begin() + static_cast<std::ptrdiff_t>(begin), array.begin() + static_cast<std::ptrdiff_t>(end), to);
  };
  for (auto* v : {&pb_mid, &beta_b, &pc_mid, &beta_c, &weight, &k_mid, &value}) set(*v, 0.0f);
  for (auto* v : {&k_first, &in_first, &stride_a, &stride_b, &stride_c}) set(*v, 0);
  for (auto* v : {&k_last, &in_last, &axis}) set(*v, -1);
  for (auto* v : {&n_b, &n_c}) set(*v, 1);
}

}  // namespace ctk::detail

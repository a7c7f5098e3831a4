// Voxel-driven back projection: one SIMD kernel per x86 target (Highway, chosen at run time) for
// a row of voxels along x, and the drivers.
#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "voxel_backprojection.cpp"
#include <hwy/foreach_target.h>  // IWYU pragma: keep
#include <hwy/highway.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <stdexcept>

#include "ctk/proj/ray_geometry.hpp"
#include "ctk/proj/voxel_backprojection.hpp"
#include "window_lookup-inl.h"

// What a row kernel needs: the homogeneous pixel P X of the row's first voxel and its step per
// voxel (float: |P X| reaches 1e6 here, so u carries ~1e-5 px of rounding), the image, the weight.
#ifndef CTK_PROJ_VOXEL_ROW_DEFINED
#define CTK_PROJ_VOXEL_ROW_DEFINED
namespace ctk::detail {
struct VoxelRow {
  float p0[3], dp[3];
  const float* image;
  int cols, rows;
  float scale2;  // scale_mm^2
  int voxels;
};
}  // namespace ctk::detail
#endif

HWY_BEFORE_NAMESPACE();
namespace ctk::detail {
namespace HWY_NAMESPACE {
namespace hn = hwy::HWY_NAMESPACE;

// The four corners (u0, v0), (u1, v0), (u0, v1), (u1, v1) of every lane without gathers, when
// the lanes that touch the detector fall within 2N columns and three rows: those rows are
// loaded whole and each lane picks its corners by permutes. A row of voxels usually projects so
// (along a detector row, or to nearly one pixel); false otherwise, and the caller gathers.
template <class DF, class MI, class VI = hn::Vec<hn::RebindToSigned<DF>>>
HWY_INLINE bool window_corners(DF df, const VoxelRow& r, MI touches, VI iu0, VI iu1, VI iv0, VI iv1, hn::Vec<DF>& g00,
                               hn::Vec<DF>& g10, hn::Vec<DF>& g01, hn::Vec<DF>& g11) {
#if HWY_TARGET == HWY_SCALAR
  (void)df, (void)r, (void)touches, (void)iu0, (void)iu1, (void)iv0, (void)iv1, (void)g00, (void)g10, (void)g01, (void)g11;
  return false;
#else
  const hn::RebindToSigned<DF> di;
  const int N = static_cast<int>(hn::Lanes(df));
  if (r.cols < 2 * N || r.rows < 3) return false;
  const auto far = hn::Set(di, 1 << 29);
  const int x0 = std::min(hn::GetLane(hn::MinOfLanes(di, hn::IfThenElse(touches, iu0, far))), r.cols - 2 * N);
  const int y0 = std::min(hn::GetLane(hn::MinOfLanes(di, hn::IfThenElse(touches, iv0, far))), r.rows - 3);
  // Lanes off the detector (weight zero) read the window's first voxel.
  const auto pos0 = hn::IfThenElseZero(touches, hn::Sub(iu0, hn::Set(di, x0)));
  const auto pos1 = hn::IfThenElseZero(touches, hn::Sub(iu1, hn::Set(di, x0)));
  const auto row0 = hn::IfThenElseZero(touches, hn::Sub(iv0, hn::Set(di, y0)));
  const auto row1 = hn::IfThenElseZero(touches, hn::Sub(iv1, hn::Set(di, y0)));
  if (!hn::AllTrue(di, hn::Lt(pos1, hn::Set(di, 2 * N))) || !hn::AllTrue(di, hn::Lt(row1, hn::Set(di, 3)))) return false;
  const float* base = r.image + static_cast<std::ptrdiff_t>(y0) * r.cols + x0;
  hn::Vec<DF> at0[3], at1[3];  // row j at pos0 and at pos1
  for (int j = 0; j < 3; ++j) {
    const auto lo = hn::LoadU(df, base + j * r.cols), hi = hn::LoadU(df, base + j * r.cols + N);
    at0[j] = lookup_window(df, lo, hi, pos0);
    at1[j] = lookup_window(df, lo, hi, pos1);
  }
  const auto pick = [&](VI row, const hn::Vec<DF>(&at)[3]) {
    return hn::IfThenElse(hn::RebindMask(df, hn::Eq(row, hn::Set(di, 2))), at[2],
                          hn::IfThenElse(hn::RebindMask(df, hn::Eq(row, hn::Set(di, 1))), at[1], at[0]));
  };
  g00 = pick(row0, at0), g10 = pick(row0, at1), g01 = pick(row1, at0), g11 = pick(row1, at1);
  return true;
#endif
}

// (scale / depth)^2 image(P X) for the voxels i of the row (fractional x index per lane). A
// corner of the bilinear footprint off the detector has weight zero (its index is clamped so the
// read stays inside the image).
template <class DF>
HWY_INLINE hn::Vec<DF> row_values(DF df, const VoxelRow& r, hn::Vec<DF> i) {
  const hn::RebindToSigned<DF> di;
  const auto pz = hn::MulAdd(i, hn::Set(df, r.dp[2]), hn::Set(df, r.p0[2]));
  const auto in_front = hn::Gt(pz, hn::Zero(df));
  const auto inv = hn::Div(hn::Set(df, 1.0f), hn::IfThenElse(in_front, pz, hn::Set(df, 1.0f)));
  const auto u = hn::Mul(hn::MulAdd(i, hn::Set(df, r.dp[0]), hn::Set(df, r.p0[0])), inv);
  const auto v = hn::Mul(hn::MulAdd(i, hn::Set(df, r.dp[1]), hn::Set(df, r.p0[1])), inv);
  const auto last_u = hn::Set(df, static_cast<float>(r.cols - 1)), last_v = hn::Set(df, static_cast<float>(r.rows - 1));
  const auto minus_one = hn::Set(df, -1.0f), one = hn::Set(df, 1.0f), zero = hn::Zero(df);
  // Footprints touching the detector: -1 <= floor(u) <= cols - 1 (NaN compares false).
  const auto uf = hn::Floor(u), vf = hn::Floor(v);
  const auto touches = hn::And(
      in_front, hn::And(hn::And(hn::Ge(uf, minus_one), hn::Le(uf, last_u)), hn::And(hn::Ge(vf, minus_one), hn::Le(vf, last_v))));
  const auto u0 = hn::IfThenElse(touches, uf, zero), v0 = hn::IfThenElse(touches, vf, zero);
  const auto fu = hn::IfThenElseZero(touches, hn::Sub(u, uf)), fv = hn::IfThenElseZero(touches, hn::Sub(v, vf));
  // Corner weights, zero for corners off the detector.
  const auto wu0 = hn::IfThenElseZero(hn::Ge(u0, zero), hn::Sub(one, fu));
  const auto wu1 = hn::IfThenElseZero(hn::Lt(u0, last_u), fu);
  const auto wv0 = hn::IfThenElseZero(hn::And(touches, hn::Ge(v0, zero)), hn::Sub(one, fv));
  const auto wv1 = hn::IfThenElseZero(hn::And(touches, hn::Lt(v0, last_v)), fv);
  const auto cols = hn::Set(di, r.cols);
  const auto iu0 = hn::ConvertTo(di, hn::Max(u0, zero)), iu1 = hn::ConvertTo(di, hn::Min(hn::Add(u0, one), last_u));
  const auto iv0 = hn::ConvertTo(di, hn::Max(v0, zero)), iv1 = hn::ConvertTo(di, hn::Min(hn::Add(v0, one), last_v));
  hn::Vec<DF> g00, g10, g01, g11;
  if (!window_corners(df, r, hn::RebindMask(di, touches), iu0, iu1, iv0, iv1, g00, g10, g01, g11)) {
    const auto row0 = hn::Mul(iv0, cols), row1 = hn::Mul(iv1, cols);
    g00 = hn::GatherIndex(df, r.image, hn::Add(row0, iu0)), g10 = hn::GatherIndex(df, r.image, hn::Add(row0, iu1));
    g01 = hn::GatherIndex(df, r.image, hn::Add(row1, iu0)), g11 = hn::GatherIndex(df, r.image, hn::Add(row1, iu1));
  }
  const auto value =
      hn::MulAdd(wv0, hn::MulAdd(wu0, g00, hn::Mul(wu1, g10)), hn::Mul(wv1, hn::MulAdd(wu0, g01, hn::Mul(wu1, g11))));
  return hn::Mul(value, hn::Mul(hn::Set(df, r.scale2), hn::Mul(inv, inv)));
}

void BackprojectRow(const VoxelRow& r, float* HWY_RESTRICT row) {
  const hn::ScalableTag<float> df;
  const int N = static_cast<int>(hn::Lanes(df));
  int i = 0;
  for (; i + N <= r.voxels; i += N) {
    const auto index = hn::Add(hn::Iota(df, 0.0f), hn::Set(df, static_cast<float>(i)));
    hn::StoreU(hn::Add(hn::LoadU(df, row + i), row_values(df, r, index)), df, row + i);
  }
  if (i < r.voxels) {  // the tail through a full-width buffer
    HWY_ALIGN float tail[hn::MaxLanes(df)];
    hn::Store(row_values(df, r, hn::Add(hn::Iota(df, 0.0f), hn::Set(df, static_cast<float>(i)))), df, tail);
    for (int l = 0; i + l < r.voxels; ++l) row[i + l] += tail[l];
  }
}

}  // namespace HWY_NAMESPACE
}  // namespace ctk::detail
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
namespace ctk {
namespace detail {
HWY_EXPORT(BackprojectRow);
}  // namespace detail

namespace {

void check_inputs(const ProjectionStack& q, const std::vector<ProjectionMatrix>& views, double scale_mm) {
  check_stack_matches_views(q.views, q.rows, q.cols, views.size());
  if (!(scale_mm > 0)) throw std::invalid_argument("voxel_backproject: the weight's scale must be positive");
}

}  // namespace

void voxel_backproject(const ProjectionStack& q, const std::vector<ProjectionMatrix>& views, double scale_mm, Volume& x) {
  check_inputs(q, views, scale_mm);
  std::fill(x.data.begin(), x.data.end(), 0.0f);
  const auto& n = x.layout.size;
  const Eigen::Vector3d step_i(x.layout.voxel_mm.x(), 0, 0);
  // A block of a z slice's rows stays in cache while every view adds to it, and meets only a
  // band of each view's rows on a circular scan. Blocks of rows rather than whole slices, so that a
  // volume of few slices (one, for a fan beam) still keeps every core busy; each voxel still adds
  // the views in their order, so the result does not depend on the blocks.
  constexpr int kRowsPerBlock = 16;
  const int blocks = (n[1] + kRowsPerBlock - 1) / kRowsPerBlock;
#pragma omp parallel for schedule(dynamic)
  for (int task = 0; task < n[2] * blocks; ++task) {
    const int k = task / blocks, j_begin = (task % blocks) * kRowsPerBlock, j_end = std::min(n[1], j_begin + kRowsPerBlock);
    for (std::size_t v = 0; v < views.size(); ++v) {
      const Matrix34d& P = views[v].matrix();
      detail::VoxelRow r{};
      const Eigen::Vector3d dp = P.leftCols<3>() * step_i;
      for (int a = 0; a < 3; ++a) r.dp[a] = static_cast<float>(dp[a]);
      r.image = q.view(static_cast<int>(v));
      r.cols = q.cols;
      r.rows = q.rows;
      r.scale2 = static_cast<float>(scale_mm * scale_mm);
      r.voxels = n[0];
      for (int j = j_begin; j < j_end; ++j) {
        const Eigen::Vector3d p0 = P.leftCols<3>() * x.layout.centre_of(0, j, k) + P.col(3);
        for (int a = 0; a < 3; ++a) r.p0[a] = static_cast<float>(p0[a]);
        HWY_DYNAMIC_DISPATCH(detail::BackprojectRow)(r, &x.at(0, j, k));
      }
    }
  }
}

void voxel_backproject_reference(const ProjectionStack& q, const std::vector<ProjectionMatrix>& views, double scale_mm,
                                 Volume& x) {
  check_inputs(q, views, scale_mm);
  const int cols = q.cols, rows = q.rows;
  const auto& n = x.layout.size;
  for (int k = 0; k < n[2]; ++k)
    for (int j = 0; j < n[1]; ++j)
      for (int i = 0; i < n[0]; ++i) {
        double sum = 0;
        for (std::size_t v = 0; v < views.size(); ++v) {
          const Eigen::Vector3d p = views[v].matrix() * x.layout.centre_of(i, j, k).homogeneous();
          if (p.z() <= 0) continue;  // behind the source
          const double u = p.x() / p.z(), w = p.y() / p.z();
          if (!(u > -2 && w > -2 && u < cols + 1 && w < rows + 1)) continue;  // off the detector
          const int u0 = static_cast<int>(std::floor(u)), w0 = static_cast<int>(std::floor(w));
          const double fu = u - u0, fw = w - w0;
          auto at = [&](int uu, int ww) -> double {
            if (uu < 0 || ww < 0 || uu >= cols || ww >= rows) return 0.0;
            return q.at(static_cast<int>(v), ww, uu);
          };
          const double value = (1 - fw) * ((1 - fu) * at(u0, w0) + fu * at(u0 + 1, w0)) +
                               fw * ((1 - fu) * at(u0, w0 + 1) + fu * at(u0 + 1, w0 + 1));
          sum += value * (scale_mm / p.z()) * (scale_mm / p.z());
        }
        x.at(i, j, k) = static_cast<float>(sum);
      }
}

}  // namespace ctk
#endif

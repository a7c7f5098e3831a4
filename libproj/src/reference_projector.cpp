#include "ctk/proj/reference_projector.hpp"

#include <cmath>
#include <stdexcept>

#include "ctk/proj/ray_geometry.hpp"

namespace ctk {

namespace {

// Calls visit(voxel index, weight) for every bilinear corner of every Joseph sample of the ray.
// Corners outside the volume are skipped (they read as zero).
template <typename Visit>
void visit_ray(const MarchedRay& m, const VolumeLayout& layout, Visit&& visit) {
  const int a = m.axis;
  const auto [b, c] = other_axes(a);
  const auto stride = layout.strides();
  const int nb = layout.size[static_cast<std::size_t>(b)], nc = layout.size[static_cast<std::size_t>(c)];
  const double k_mid = 0.5 * (layout.size[static_cast<std::size_t>(a)] - 1);
  for (int k = m.k_first; k <= m.k_last; ++k) {
    const double pb = m.pb_mid + (k - k_mid) * m.beta_b;
    const double pc = m.pc_mid + (k - k_mid) * m.beta_c;
    const int ib = static_cast<int>(std::floor(pb)), ic = static_cast<int>(std::floor(pc));
    const double fb = pb - ib, fc = pc - ic;
    const double corner_weight[2][2] = {{(1 - fb) * (1 - fc), (1 - fb) * fc}, {fb * (1 - fc), fb * fc}};
    for (int db = 0; db < 2; ++db) {
      for (int dc = 0; dc < 2; ++dc) {
        const int jb = ib + db, jc = ic + dc;
        if (jb < 0 || jb >= nb || jc < 0 || jc >= nc) continue;
        const std::ptrdiff_t index = k * stride[static_cast<std::size_t>(a)] + jb * stride[static_cast<std::size_t>(b)] +
                                     jc * stride[static_cast<std::size_t>(c)];
        visit(static_cast<std::size_t>(index), m.weight_mm * corner_weight[db][dc]);
      }
    }
  }
}

}  // namespace

void forward_project_reference(const Volume& x, const std::vector<ProjectionMatrix>& views, ProjectionStack& y) {
  check_stack_matches_views(y.views, y.rows, y.cols, views.size());
  for (int v = 0; v < y.views; ++v) {
    const ViewRays rays = view_rays(views[static_cast<std::size_t>(v)], x.layout);
    for (int row = 0; row < y.rows; ++row) {
      for (int col = 0; col < y.cols; ++col) {
        double sum = 0;
        visit_ray(march_ray(rays, x.layout, col, row), x.layout, [&](std::size_t i, double w) { sum += w * x.data[i]; });
        y.at(v, row, col) = static_cast<float>(sum);
      }
    }
  }
}

void back_project_reference(const ProjectionStack& y, const std::vector<ProjectionMatrix>& views, Volume& x) {
  check_stack_matches_views(y.views, y.rows, y.cols, views.size());
  std::vector<double> acc(x.data.size(), 0.0);
  for (int v = 0; v < y.views; ++v) {
    const ViewRays rays = view_rays(views[static_cast<std::size_t>(v)], x.layout);
    for (int row = 0; row < y.rows; ++row) {
      for (int col = 0; col < y.cols; ++col) {
        const double value = y.at(v, row, col);
        if (value == 0) continue;
        visit_ray(march_ray(rays, x.layout, col, row), x.layout, [&](std::size_t i, double w) { acc[i] += w * value; });
      }
    }
  }
  for (std::size_t i = 0; i < acc.size(); ++i) x.data[i] = static_cast<float>(acc[i]);
}

}  // namespace ctk

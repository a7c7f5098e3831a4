// Uses an installed ctk as a lab's own program would: a Joseph projector on a few views, its
// adjoint checked, a projection matrix decomposed. Exit 0 when both hold.
#include <cmath>
#include <cstdio>
#include <random>

#include "ctk/geom/trajectory.hpp"
#include "ctk/proj/joseph_operator.hpp"

int main() {
  const ctk::Detector detector{32, 24, 1.0, 1.0};
  const ctk::Intrinsics K = ctk::Intrinsics::from_setup(500, detector, detector.centre_px());
  std::vector<ctk::ProjectionMatrix> views;
  for (int v = 0; v < 6; ++v) {
    const double a = 0.5 * v;
    views.push_back(ctk::ProjectionMatrix::compose(
        K, ctk::make_rigid(ctk::rotation_looking_along(Eigen::Vector3d(std::cos(a), std::sin(a), 0.3).normalized()),
                           Eigen::Vector3d(0, 0, 300))));
  }
  const ctk::VolumeLayout layout = ctk::VolumeLayout::centred({12, 12, 12}, Eigen::Vector3d::Constant(1.0));
  const ctk::JosephOperator A(views, layout, detector.rows, detector.cols);
  std::mt19937 random(1);
  std::uniform_real_distribution<float> uniform(-1, 1);
  ctk::Volume x(layout), back;
  for (float& v : x.data) v = uniform(random);
  ctk::ProjectionStack y = A.range_zeros(), Ax;
  for (float& v : y.data) v = uniform(random);
  A.apply(x, Ax);
  A.apply_adjoint(y, back);
  double ax_y = 0, x_aty = 0;
  for (std::size_t i = 0; i < Ax.data.size(); ++i) ax_y += double(Ax.data[i]) * y.data[i];
  for (std::size_t i = 0; i < x.data.size(); ++i) x_aty += double(x.data[i]) * back.data[i];
  const double relative = std::abs(ax_y - x_aty) / std::abs(x_aty);
  const double depth = views[0].decompose().T_camera_frame.translation().z();
  std::printf("installed ctk: <A x, y> %.6g, <x, A' y> %.6g (relative %.1e); depth %.3f mm\n", ax_y, x_aty, relative, depth);
  return relative < 1e-5 && std::abs(depth - 300) < 1e-9 ? 0 : 1;
}

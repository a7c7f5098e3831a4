#include "ctk/proj/standard_problem.hpp"

#include "ctk/geom/trajectory.hpp"

namespace ctk {

StandardProblem standard_problem(StandardTrajectory trajectory, int views, int scale) {
  StandardProblem p;
  const int n = 256 / scale;
  p.layout = VolumeLayout::centred({n, n, n}, Eigen::Vector3d::Constant(1.0 * scale));
  p.rows = p.cols = 256 / scale;
  const Detector detector{p.cols, p.rows, 1.6 * scale, 1.6 * scale};
  const Intrinsics K = Intrinsics::from_setup(1500.0, detector, detector.centre_px());
  std::vector<Eigen::Vector3d> directions;
  if (trajectory == StandardTrajectory::circular) {
    p.trajectory = "circular";
    for (const auto& R : circular_rotations(Eigen::Vector3d::UnitZ(), views, 0.0, 2 * M_PI))
      directions.push_back(R * Eigen::Vector3d::UnitX());
  } else {
    p.trajectory = "spherical";
    directions = random_directions(views, 2026);
  }
  for (const auto& d : directions) {
    const Eigen::Matrix3d R = rotation_looking_along(d);
    p.views.push_back(ProjectionMatrix::compose(K, make_rigid(R, Eigen::Vector3d(0, 0, 1000.0))));
  }
  return p;
}

}  // namespace ctk

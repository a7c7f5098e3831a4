#include "ctk/phantoms/panda_ik.hpp"

#include <ceres/ceres.h>
#include <ceres/rotation.h>

namespace ctk {

namespace {

constexpr double kRotationWeightMm = 100.0;  // 1 rad of orientation error weighs as 100 mm

struct FlangePoseError {
  Eigen::Matrix3d R_target;
  Eigen::Vector3d t_target;

  template <typename T>
  bool operator()(const T* q, T* residual) const {
    const Eigen::Matrix<T, 4, 4> M = panda::forward_kinematics_matrix(q);
    for (int i = 0; i < 3; ++i) residual[i] = M(i, 3) - T(t_target(i));
    // Orientation error: rotation vector of R_target^T R(q).
    const Eigen::Matrix<T, 3, 3> E = R_target.transpose().cast<T>() * M.template topLeftCorner<3, 3>();
    T angle_axis[3];
    ceres::RotationMatrixToAngleAxis(ceres::ColumnMajorAdapter3x3(E.data()), angle_axis);
    for (int i = 0; i < 3; ++i) residual[3 + i] = T(kRotationWeightMm) * angle_axis[i];
    return true;
  }
};

}  // namespace

IkSolution solve_panda_ik(const Rigid& T_base_flange, const panda::Joints& start, double margin_rad) {
  IkSolution solution;
  solution.q = start;
  const auto& limits = panda::joint_limits();
  for (int i = 0; i < panda::kJointCount; ++i)
    solution.q[static_cast<std::size_t>(i)] =
        std::clamp(solution.q[static_cast<std::size_t>(i)], limits[static_cast<std::size_t>(i)].lower_rad + margin_rad,
                   limits[static_cast<std::size_t>(i)].upper_rad - margin_rad);

  ceres::Problem problem;
  auto* cost = new ceres::AutoDiffCostFunction<FlangePoseError, 6, panda::kJointCount>(
      new FlangePoseError{T_base_flange.linear(), T_base_flange.translation()});
  problem.AddResidualBlock(cost, nullptr, solution.q.data());
  for (int i = 0; i < panda::kJointCount; ++i) {
    problem.SetParameterLowerBound(solution.q.data(), i, limits[static_cast<std::size_t>(i)].lower_rad + margin_rad);
    problem.SetParameterUpperBound(solution.q.data(), i, limits[static_cast<std::size_t>(i)].upper_rad - margin_rad);
  }
  ceres::Solver::Options options;
  options.max_num_iterations = 200;
  options.function_tolerance = 1e-16;
  options.parameter_tolerance = 1e-14;
  options.gradient_tolerance = 1e-16;
  options.logging_type = ceres::SILENT;
  ceres::Solver::Summary summary;
  ceres::Solve(options, &problem, &summary);

  const Rigid reached = panda::forward_kinematics(solution.q);
  solution.position_error_mm = (reached.translation() - T_base_flange.translation()).norm();
  solution.rotation_error_deg = rotation_angle_deg(T_base_flange.linear().transpose() * reached.linear());
  solution.reached = solution.position_error_mm < 1e-4 && solution.rotation_error_deg < 1e-5;
  return solution;
}

}  // namespace ctk

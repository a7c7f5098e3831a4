#include "ctk/calib/scan_model_fit.hpp"

#include <ceres/ceres.h>
#include <ceres/normal_prior.h>
#include <ceres/rotation.h>

#include <algorithm>
#include <cmath>

#include "ctk/calib/marginal_covariance.hpp"
#include "ctk/core/parallel.hpp"
#include "small_problem.hpp"

namespace ctk {

namespace {

constexpr double kDegree = M_PI / 180.0;

template <typename T>
using Mat3 = Eigen::Matrix<T, 3, 3>;
template <typename T>
using Vec3 = Eigen::Matrix<T, 3, 1>;

// The pose block: rotation vector applied on top of the view's starting rotation R0, and the
// camera-frame translation.
template <typename T>
void pose_of(const T* pose, const Eigen::Matrix3d& R0, Mat3<T>& R, Vec3<T>& t) {
  Mat3<T> Rw;
  ceres::AngleAxisToRotationMatrix(pose, ceres::ColumnMajorAdapter3x3(Rw.data()));
  R = Rw * R0.cast<T>();
  t = Vec3<T>(pose[3], pose[4], pose[5]);
}

template <typename T>
Eigen::Matrix<T, 4, 4> offset_matrix(const T* p) {
  Eigen::Matrix<T, 4, 4> M = Eigen::Matrix<T, 4, 4>::Identity();
  Mat3<T> R;
  ceres::AngleAxisToRotationMatrix(p, ceres::ColumnMajorAdapter3x3(R.data()));
  M.template topLeftCorner<3, 3>() = R;
  M.template topRightCorner<3, 1>() = Vec3<T>(p[3], p[4], p[5]);
  return M;
}

template <typename T>
Eigen::Matrix<T, 4, 4> rigid_inverse(const Eigen::Matrix<T, 4, 4>& M) {
  Eigen::Matrix<T, 4, 4> I = Eigen::Matrix<T, 4, 4>::Identity();
  const Mat3<T> Rt = M.template topLeftCorner<3, 3>().transpose();
  I.template topLeftCorner<3, 3>() = Rt;
  I.template topRightCorner<3, 1>() = -Rt * M.template topRightCorner<3, 1>();
  return I;
}

// One matched sphere in one view: measured centre against the model's projection.
struct ImageResidual {
  Eigen::Matrix3d R0;
  Eigen::Vector3d X;
  Eigen::Vector2d measured;
  Intrinsics K;
  double pitch_u, pitch_v, view, weight;
  Eigen::Vector2d declared_drift;  // mm per 100 views; the effect's parameters add to it

  template <typename T>
  bool operator()(const T* pose, const T* sphere, const T* intrinsics, const T* distortion, const T* drift, T* r) const {
    Mat3<T> R;
    Vec3<T> t;
    pose_of(pose, R0, R, t);
    const Vec3<T> Xs = X.cast<T>() + Vec3<T>(sphere[0], sphere[1], sphere[2]);
    const Vec3<T> s = drifted_focal_spot_mm(drift[0] + T(declared_drift.x()), drift[1] + T(declared_drift.y()), view);
    const T s0 = s.x(), s1 = s.y();  // NOLINT(performance-unnecessary-copy-initialization): Jets, read twice
    const Vec3<T> Y = R * Xs + t - s;
    // Seen from the moved focal spot the principal point moves with it (detector fixed).
    const T fu = T(K.fu_px) + intrinsics[2], fv = T(K.fv_px) + intrinsics[2] * T(K.fv_px / K.fu_px);
    const T u0 = T(K.u0_px) + intrinsics[0] + s0 / T(pitch_u), v0 = T(K.v0_px) + intrinsics[1] + s1 / T(pitch_v);
    T u = fu * Y.x() / Y.z() + T(K.skew_px) * Y.y() / Y.z() + u0;
    T v = fv * Y.y() / Y.z() + v0;
    const T du = u - (T(K.u0_px) + distortion[1]), dv = v - (T(K.v0_px) + distortion[2]);
    const T k1 = distortion[0] / T(360.0 * 360.0 * 360.0), r2 = du * du + dv * dv;
    u += k1 * r2 * du;
    v += k1 * r2 * dv;
    r[0] = (u - T(measured.x())) * T(weight);
    r[1] = (v - T(measured.y())) * T(weight);
    return true;
  }
};

// The robot's repeatability: the pose relative to the model's prediction, as a perturbation at
// the flange, in units of its standard deviation per axis.
struct RobotPrior {
  Eigen::Matrix3d R0;
  panda::Joints q;
  Eigen::Matrix4d T_camera_base, T_flange_holder;
  double sigma_mm, sigma_rad;

  template <typename T>
  bool operator()(const T* pose, const T* base, const T* mount, const T* joints, const T* gravity, T* r) const {
    Mat3<T> R;
    Vec3<T> t;
    pose_of(pose, R0, R, t);
    Eigen::Matrix<T, 4, 4> Tv = Eigen::Matrix<T, 4, 4>::Identity();
    Tv.template topLeftCorner<3, 3>() = R;
    Tv.template topRightCorner<3, 1>() = t;
    T qt[panda::kJointCount];
    for (int j = 0; j < panda::kJointCount; ++j) qt[j] = T(q[static_cast<std::size_t>(j)]) + joints[j];
    const Eigen::Matrix<T, 4, 4> base_flange = panda::forward_kinematics_matrix(qt);
    const Eigen::Matrix<T, 4, 4> before_flange = T_camera_base.cast<T>() * offset_matrix(base) * base_flange;
    const Eigen::Matrix<T, 6, 1> load =
        gravity_load_offset<T>(base_flange.template topLeftCorner<3, 3>(), T_flange_holder.topLeftCorner<3, 3>().col(2), gravity);
    const Eigen::Matrix<T, 4, 4> after_flange = offset_matrix(mount) * offset_matrix(load.data()) * T_flange_holder.cast<T>();
    const Eigen::Matrix<T, 4, 4> N = rigid_inverse(before_flange) * Tv * rigid_inverse(after_flange);
    const Mat3<T> NR = N.template topLeftCorner<3, 3>();
    T aa[3];
    ceres::RotationMatrixToAngleAxis(ceres::ColumnMajorAdapter3x3(NR.data()), aa);
    for (int i = 0; i < 3; ++i) {
      r[i] = aa[i] / T(sigma_rad);
      r[3 + i] = N(i, 3) / T(sigma_mm);
    }
    return true;
  }
};

// Gauge of the sphere offsets: no net translation, rotation or scaling of the declared list.
struct SphereGauge {
  std::vector<Eigen::Vector3d> X;  // declared centres relative to their centroid
  double weight;

  template <typename T>
  bool operator()(T const* const* offsets, T* r) const {
    Vec3<T> sum = Vec3<T>::Zero(), turn = Vec3<T>::Zero();
    T scale(0.0);
    for (std::size_t k = 0; k < X.size(); ++k) {
      const Vec3<T> d(offsets[k][0], offsets[k][1], offsets[k][2]);
      sum += d;
      turn += X[k].cast<T>().cross(d);
      scale += X[k].cast<T>().dot(d);
    }
    for (int i = 0; i < 3; ++i) {
      r[i] = sum[i] * T(weight);
      r[3 + i] = turn[i] * T(weight / 30.0);
    }
    r[6] = scale * T(weight / 30.0);
    return true;
  }
};

// Parameter blocks shared by all views, laid out so Ceres can hold pointers into them.
struct GlobalBlocks {
  EffectParameters p;
  explicit GlobalBlocks(const EffectParameters& start, std::size_t spheres) : p(start) {
    p.spheres.resize(spheres, Eigen::Vector3d::Zero());
  }
  double* block(Effect e, std::size_t sphere = 0) {
    switch (e) {
      case Effect::robot_base_frame:
        return p.base;
      case Effect::holder_mount:
        return p.mount;
      case Effect::joint_offsets:
        return p.joints;
      case Effect::source_drift:
        return p.drift;
      case Effect::detector_intrinsics:
        return p.intrinsics;
      case Effect::detector_distortion:
        return p.distortion;
      case Effect::sphere_positions:
        return p.spheres[sphere].data();
      case Effect::gravity_load:
        return p.gravity;
    }
    return nullptr;
  }
};

int block_size(Effect e) {
  switch (e) {
    case Effect::robot_base_frame:
    case Effect::holder_mount:
      return 6;
    case Effect::joint_offsets:
      return 7;
    case Effect::source_drift:
    case Effect::gravity_load:
      return 2;
    case Effect::detector_intrinsics:
    case Effect::detector_distortion:
    case Effect::sphere_positions:
      return 3;
  }
  return 0;
}

// The scale of each effect's parameters in a real setup, far beyond any error a lab leaves: a
// weak Gaussian prior at this scale fixes the directions the data leave free (on a joint-7 orbit
// a mount shift along the flange axis is a base shift along the joint's axis) at their smallest
// value, where an unfixed fit wanders metres away and takes noise along; it changes an
// identifiable parameter by far less than its uncertainty.
Eigen::VectorXd plausible_scale(Effect e) {
  const double deg = kDegree;
  Eigen::VectorXd s(block_size(e));
  switch (e) {
    case Effect::robot_base_frame:
    case Effect::holder_mount:
      s << 5 * deg, 5 * deg, 5 * deg, 50, 50, 50;
      break;  // rad, mm
    case Effect::joint_offsets:
      s.setConstant(5 * deg);
      break;
    case Effect::source_drift:
      s << 10, 10;
      break;  // mm per 100 views
    case Effect::detector_intrinsics:
      s << 50, 50, 200;
      break;  // px
    case Effect::detector_distortion:
      s << 50, 200, 200;
      break;  // px
    case Effect::gravity_load:
      s << 1 * deg, 5;
      break;  // rad, mm at a horizontal holder
    case Effect::sphere_positions:
      s.resize(0);
      break;  // fixed by the sphere gauge instead
  }
  return s;
}

std::array<double, 6> start_pose(const Rigid& T) {
  return {0, 0, 0, T.translation().x(), T.translation().y(), T.translation().z()};
}

Rigid pose_from_block(const double* pose, const Eigen::Matrix3d& R0) {
  Eigen::Matrix3d R;
  Eigen::Vector3d t;
  pose_of(pose, R0, R, t);
  return make_rigid(R, t);
}

// Adds one view's residual blocks: one per matched sphere, and the robot prior.
void add_view(ceres::Problem& problem, const ScanObservations& o, const ViewObservations& v, double* pose, GlobalBlocks& g) {
  const DeclaredSetup& s = o.setup;
  const Eigen::Matrix3d R0 = v.T_calibrated.linear();
  for (std::size_t i = 0; i < v.spheres.size(); ++i) {
    const auto k = static_cast<std::size_t>(v.spheres[i]);
    auto* f = new ImageResidual{R0,
                                s.holder.spheres_mm[k],
                                v.measured_px[i],
                                s.K,
                                s.detector.pitch_u_mm,
                                s.detector.pitch_v_mm,
                                static_cast<double>(v.view),
                                1.0 / centre_sigma(o, v),
                                s.source_drift_mm_per_100_views};
    problem.AddResidualBlock(new ceres::AutoDiffCostFunction<ImageResidual, 2, 6, 3, 3, 3, 2>(f), nullptr, pose,
                             g.block(Effect::sphere_positions, k), g.block(Effect::detector_intrinsics),
                             g.block(Effect::detector_distortion), g.block(Effect::source_drift));
  }
  if (s.robot && v.joints) {
    auto* f = new RobotPrior{R0,
                             *v.joints,
                             s.T_camera_base.matrix(),
                             s.T_flange_holder.matrix(),
                             o.robot_sigma_mm / std::sqrt(3.0),
                             o.robot_sigma_deg * kDegree / std::sqrt(3.0)};
    problem.AddResidualBlock(new ceres::AutoDiffCostFunction<RobotPrior, 6, 6, 6, 6, 7, 2>(f), nullptr, pose,
                             g.block(Effect::robot_base_frame), g.block(Effect::holder_mount), g.block(Effect::joint_offsets),
                             g.block(Effect::gravity_load));
  }
}

void set_global_blocks_constant(ceres::Problem& problem, GlobalBlocks& g, const std::vector<Effect>& active) {
  for (Effect e : kModelledEffects) {
    if (std::find(active.begin(), active.end(), e) != active.end()) continue;
    if (e == Effect::sphere_positions) {
      for (std::size_t k = 0; k < g.p.spheres.size(); ++k)
        if (problem.HasParameterBlock(g.block(e, k))) problem.SetParameterBlockConstant(g.block(e, k));
    } else if (problem.HasParameterBlock(g.block(e))) {
      problem.SetParameterBlockConstant(g.block(e));
    }
  }
}

// Per-view results from the solved blocks.
void collect_view(const ScanObservations& o, const ViewObservations& v, const double* pose, const EffectParameters& p,
                  ScanModelFit& out, std::size_t slot) {
  const Eigen::Matrix3d R0 = v.T_calibrated.linear();
  out.poses[slot] = pose_from_block(pose, R0);
  double sq = 0;
  out.residual_px[slot].clear();
  for (std::size_t i = 0; i < v.spheres.size(); ++i) {
    const auto k = static_cast<std::size_t>(v.spheres[i]);
    const ImageResidual f{R0,
                          o.setup.holder.spheres_mm[k],
                          v.measured_px[i],
                          o.setup.K,
                          o.setup.detector.pitch_u_mm,
                          o.setup.detector.pitch_v_mm,
                          static_cast<double>(v.view),
                          1.0,
                          o.setup.source_drift_mm_per_100_views};
    double r[2];
    f(pose, p.spheres[k].data(), p.intrinsics, p.distortion, p.drift, r);
    // f gives model - measured; the residual shown is measured - model.
    out.residual_px[slot].emplace_back(-r[0], -r[1]);
    sq += r[0] * r[0] + r[1] * r[1];
  }
  const double image = sq / (centre_sigma(o, v) * centre_sigma(o, v));
  double prior = 0;
  if (o.setup.robot && v.joints) {
    const RobotPrior f{R0,
                       *v.joints,
                       o.setup.T_camera_base.matrix(),
                       o.setup.T_flange_holder.matrix(),
                       o.robot_sigma_mm / std::sqrt(3.0),
                       o.robot_sigma_deg * kDegree / std::sqrt(3.0)};
    double r[6];
    f(pose, p.base, p.mount, p.joints, p.gravity, r);
    for (double x : r) prior += x * x;
  }
  out.cost[slot] = image + prior;
  out.image_sq_px[slot] = sq;
  out.residual_count[slot] = static_cast<int>(2 * v.spheres.size());
}

void size_result(ScanModelFit& out, std::size_t n) {
  out.poses.resize(n);
  out.cost.assign(n, 0.0);
  out.image_sq_px.assign(n, 0.0);
  out.residual_count.assign(n, 0);
  out.residual_px.assign(n, {});
}

}  // namespace

double ScanModelFit::image_rms_px() const {
  double sq = 0;
  int n = 0;
  for (std::size_t i = 0; i < image_sq_px.size(); ++i) {
    sq += image_sq_px[i];
    n += residual_count[i] / 2;
  }
  return n > 0 ? std::sqrt(sq / n) : 0.0;
}

int parameter_count(Effect e, const ScanObservations& o) {
  return e == Effect::sphere_positions ? 3 * static_cast<int>(o.setup.holder.spheres_mm.size()) : block_size(e);
}

WaldStatistic effect_strength(const ScanModelFit& fit, const std::vector<Effect>& active, std::size_t slot) {
  if (fit.covariance.size() == 0 || slot >= active.size() || slot >= fit.covariance_offsets.size()) return {};
  const Effect e = active[slot];
  GlobalBlocks g(fit.parameters, fit.parameters.spheres.size());
  const int start = fit.covariance_offsets[slot];
  const int size = e == Effect::sphere_positions ? 3 * static_cast<int>(g.p.spheres.size()) : block_size(e);
  Eigen::VectorXd values(size);
  for (int i = 0; i < size; ++i)
    values(i) = e == Effect::sphere_positions ? g.p.spheres[static_cast<std::size_t>(i / 3)](i % 3) : g.block(e)[i];
  // A distortion's size is its shift at 360 px; its centre is undefined without one.
  const int measured = e == Effect::detector_distortion ? 1 : size;
  return wald_statistic(values.head(measured), fit.covariance.block(start, start, measured, measured));
}

namespace {

// The gauge of every centre free: the list's centroid, orientation and scale stay the declared
// ones (constraints on the offsets' sums).
void add_sphere_gauge(ceres::Problem& problem, const ScanObservations& o, GlobalBlocks& g) {
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
  for (const auto& X : o.setup.holder.spheres_mm) centroid += X;
  centroid /= static_cast<double>(o.setup.holder.spheres_mm.size());
  auto* gauge = new SphereGauge{{}, 1e3};
  auto* cost = new ceres::DynamicAutoDiffCostFunction<SphereGauge, 4>(gauge);
  std::vector<double*> blocks;
  for (std::size_t k = 0; k < o.setup.holder.spheres_mm.size(); ++k) {
    gauge->X.push_back(o.setup.holder.spheres_mm[k] - centroid);
    cost->AddParameterBlock(3);
    blocks.push_back(g.block(Effect::sphere_positions, k));
  }
  cost->SetNumResiduals(7);
  problem.AddResidualBlock(cost, nullptr, blocks);
}

ceres::Solver::Options solver_options(ceres::ParameterBlockOrdering* ordering, bool every_centre_free) {
  ceres::Solver::Options options;
  options.linear_solver_type = ceres::DENSE_SCHUR;
  options.linear_solver_ordering.reset(ordering);
  options.max_num_iterations = 50;
  options.function_tolerance = 1e-10;
  if (every_centre_free) {
    // Every centre free: the minimum is flat, and the cost stops changing (1e-10) while the
    // centres still move by micrometres; held to their own convergence instead.
    options.function_tolerance = 1e-16;
    options.parameter_tolerance = 1e-12;
    options.max_num_iterations = 200;
  }
  options.logging_type = ceres::SILENT;
  // One thread: two summed the Schur complement in an order that changed from run to run, and a
  // holder measured twice differed by 1.1 um (its second pass's matches followed).
  options.num_threads = 1;
  return options;
}

// The active effects' covariance, in their order (sphere offsets: every sphere's), into `out`.
void add_covariance(ceres::Problem& problem, GlobalBlocks& g, std::vector<std::array<double, 6>>& poses,
                    const std::vector<Effect>& active, ScanModelFit& out) {
  std::vector<const double*> blocks;
  for (Effect e : active) {
    out.covariance_offsets.push_back(0);
    if (e == Effect::sphere_positions)
      for (std::size_t k = 0; k < g.p.spheres.size(); ++k) {
        if (problem.HasParameterBlock(g.block(e, k))) blocks.push_back(g.block(e, k));
      }
    else if (problem.HasParameterBlock(g.block(e)))
      blocks.push_back(g.block(e));
  }
  int size = 0;
  for (std::size_t a = 0; a < active.size(); ++a) {
    out.covariance_offsets[a] = size;
    size += active[a] == Effect::sphere_positions ? 3 * static_cast<int>(g.p.spheres.size()) : block_size(active[a]);
  }
  // The globals' covariance with every per-view pose free (marginalised), not held at its
  // optimum: a pose and a global effect trade off (a base offset against each view's depth), and
  // holding the poses understated the globals' uncertainty (3 sigma errors in a population).
  std::vector<double*> pose_blocks;
  pose_blocks.reserve(poses.size());
  for (auto& pose : poses) pose_blocks.push_back(pose.data());
  if (!blocks.empty() && (!marginal_covariance(problem, pose_blocks, blocks, out.covariance) || out.covariance.rows() != size))
    out.covariance.resize(0, 0);
}

}  // namespace

ScanModelFit fit_scan_model(const ScanObservations& o, const std::vector<Effect>& active, const std::vector<std::size_t>& views,
                            const EffectParameters& start, bool with_covariance) {
  GlobalBlocks g(start, o.setup.holder.spheres_mm.size());
  std::vector<std::array<double, 6>> poses;
  poses.reserve(views.size());
  ceres::Problem problem;
  auto* ordering = new ceres::ParameterBlockOrdering;
  for (std::size_t i : views) {
    poses.push_back(start_pose(o.views[i].T_calibrated));
    add_view(problem, o, o.views[i], poses.back().data(), g);
    ordering->AddElementToGroup(poses.back().data(), 0);
  }
  const bool spheres_free = std::find(active.begin(), active.end(), Effect::sphere_positions) != active.end();
  // Every sphere free, listed or not, is the whole holder under the gauge; a subset is held in
  // place by the rest.
  const bool sphere_subset =
      spheres_free && std::find(start.free_spheres.begin(), start.free_spheres.end(), false) != start.free_spheres.end();
  if (spheres_free && !sphere_subset) add_sphere_gauge(problem, o, g);
  for (Effect e : kModelledEffects) {
    if (e == Effect::sphere_positions) {
      for (std::size_t k = 0; k < g.p.spheres.size(); ++k)
        if (problem.HasParameterBlock(g.block(e, k))) ordering->AddElementToGroup(g.block(e, k), 1);
    } else if (problem.HasParameterBlock(g.block(e))) {
      ordering->AddElementToGroup(g.block(e), 1);
    }
  }
  for (Effect e : active) {
    const Eigen::VectorXd scale = plausible_scale(e);
    if (scale.size() == 0 || !problem.HasParameterBlock(g.block(e))) continue;
    const ceres::Matrix A = scale.cwiseInverse().asDiagonal();
    problem.AddResidualBlock(new ceres::NormalPrior(A, ceres::Vector::Zero(scale.size())), nullptr, g.block(e));
  }
  set_global_blocks_constant(problem, g, active);
  if (sphere_subset)
    for (std::size_t k = 0; k < g.p.spheres.size(); ++k)
      if (!start.free_spheres[k] && problem.HasParameterBlock(g.block(Effect::sphere_positions, k)))
        problem.SetParameterBlockConstant(g.block(Effect::sphere_positions, k));
  const ceres::Solver::Options options = solver_options(ordering, spheres_free && !sphere_subset);
  ceres::Solver::Summary summary;
  ceres::Solve(options, &problem, &summary);

  ScanModelFit out;
  out.converged = summary.IsSolutionUsable();
  out.parameters = g.p;
  size_result(out, views.size());
  for (std::size_t i = 0; i < views.size(); ++i) collect_view(o, o.views[views[i]], poses[i].data(), g.p, out, i);

  if (with_covariance && !active.empty()) add_covariance(problem, g, poses, active, out);
  return out;
}

ScanModelFit fit_view_poses(const ScanObservations& o, const EffectParameters& model, const std::vector<std::size_t>& views) {
  ScanModelFit out;
  out.parameters = model;
  out.converged = true;
  size_result(out, views.size());
  parallel_for_dynamic(static_cast<int>(views.size()), [&](int slot) {
    const ViewObservations& v = o.views[views[static_cast<std::size_t>(slot)]];
    GlobalBlocks g(model, o.setup.holder.spheres_mm.size());
    std::array<double, 6> pose = start_pose(v.T_calibrated);
    ceres::Problem problem;
    add_view(problem, o, v, pose.data(), g);
    set_global_blocks_constant(problem, g, {});
    solve_small_problem(problem, 30);
    collect_view(o, v, pose.data(), g.p, out, static_cast<std::size_t>(slot));
  });
  return out;
}

}  // namespace ctk

#include "ctk/calib/robot_prior.hpp"

#include <algorithm>
#include <cmath>

#include <ceres/ceres.h>
#include <Eigen/Eigenvalues>

#include "ctk/calib/scan_model_fit.hpp"
#include "ctk/core/error.hpp"
#include "ctk/core/statistics.hpp"
#include "small_problem.hpp"

namespace ctk {

namespace {

constexpr double kDegree = M_PI / 180.0;
constexpr double kConsistent = 22.46;  // chi-square, 6 dof, p = 0.001
using Vector6 = Eigen::Matrix<double, 6, 1>;
using Matrix6 = Eigen::Matrix<double, 6, 6>;

// The holder's pose with the flange deviation `n` (rotation vector, translation) moved by `d`.
Rigid perturbed(const FlangeChain& chain, const Vector6& n, const Vector6& d) {
  const Rigid N = make_rigid(rotation_from_vector(d.head<3>()) * rotation_from_vector(n.head<3>()), n.tail<3>() + d.tail<3>());
  return chain.before_flange * N * chain.after_flange;
}

// What one view's spheres say about its flange deviation: J^T J / sigma^2 of their projections
// (information per unit of the deviation, the image alone).
Matrix6 image_information(const ScanObservations& o, const ViewObservations& v, const FlangeChain& chain, const Vector6& n) {
  const Eigen::Matrix3d K = o.setup.K.K();
  auto project = [&](const Vector6& d, const Eigen::Vector3d& X) -> Eigen::Vector2d {
    const Eigen::Vector3d p = K * (perturbed(chain, n, d) * X);
    return p.head<2>() / p.z();
  };
  Matrix6 information = Matrix6::Zero();
  constexpr double h = 1e-6;
  for (const int k : v.spheres) {
    const Eigen::Vector3d& X = o.setup.holder.spheres_mm[static_cast<std::size_t>(k)];
    Eigen::Matrix<double, 2, 6> J;
    for (int q = 0; q < 6; ++q) {
      Vector6 d = Vector6::Zero();
      d(q) = h;
      J.col(q) = (project(d, X) - project(-d, X)) / (2 * h);
    }
    information += J.transpose() * J;
  }
  return information / (centre_sigma(o, v) * centre_sigma(o, v));
}

struct Repeatability {
  double sigma_mm, sigma_deg;  // 3-D RMS
};

// The robot prior's information on a flange deviation (per axis: a third of the 3-D variance).
Matrix6 prior_information(const Repeatability& r) {
  const double sr = r.sigma_deg * kDegree / std::sqrt(3.0), st = r.sigma_mm / std::sqrt(3.0);
  Vector6 d;
  d << 1 / (sr * sr), 1 / (sr * sr), 1 / (sr * sr), 1 / (st * st), 1 / (st * st), 1 / (st * st);
  return d.asDiagonal();
}

// Largest per-axis rotation uncertainty (deg) of a flange-deviation covariance, in camera axes.
double rotation_sigma_deg(const FlangeChain& chain, const Matrix6& covariance) {
  const Eigen::Matrix3d R = chain.before_flange.linear();
  const Eigen::Matrix3d C = R * covariance.topLeftCorner<3, 3>() * R.transpose();
  return std::sqrt(C.diagonal().maxCoeff()) / kDegree;
}

// One view's image pose against the model: its flange deviation and the image's covariance of it.
struct Deviation {
  Vector6 n;
  Matrix6 image_covariance;
};

// Maximum likelihood of the robot's repeatability (isotropic in rotation and in translation): each
// deviation is the robot's plus the image's error, n ~ N(0, S + C). Each component then counts
// by how well the image sees it: depth, which the image barely fixes, says little about the robot.
// Alternating golden-section searches on the logarithms of the two variances.
Repeatability measure_repeatability(const std::vector<Deviation>& deviations, const Repeatability& start) {
  auto cost = [&](double log_rotation, double log_translation) {
    Vector6 s;
    s << Eigen::Vector3d::Constant(std::exp(log_rotation)), Eigen::Vector3d::Constant(std::exp(log_translation));
    double f = 0;
    for (const Deviation& d : deviations) {
      const Eigen::LDLT<Matrix6> ldlt(Matrix6(d.image_covariance + Matrix6(s.asDiagonal())));
      f += ldlt.vectorD().array().log().sum() + d.n.dot(ldlt.solve(d.n));
    }
    return f;
  };
  auto golden = [](auto&& f, double lo, double hi) {
    const double g = (std::sqrt(5.0) - 1) / 2;
    double a = hi - g * (hi - lo), b = lo + g * (hi - lo), fa = f(a), fb = f(b);
    for (int i = 0; i < 40; ++i) {
      if (fa < fb) {
        hi = b, b = a, fb = fa, a = hi - g * (hi - lo), fa = f(a);
      } else {
        lo = a, a = b, fa = fb, b = lo + g * (hi - lo), fb = f(b);
      }
    }
    return (lo + hi) / 2;
  };
  // Per-axis variances, searched from a ten-thousandth to ten thousand times the current ones.
  double r = std::log(std::pow(start.sigma_deg * kDegree, 2) / 3), t = std::log(start.sigma_mm * start.sigma_mm / 3);
  const double span = std::log(1e4);
  const double r0 = r, t0 = t;
  for (int sweep = 0; sweep < 4; ++sweep) {
    r = golden([&](double x) { return cost(x, t); }, r0 - span, r0 + span);
    t = golden([&](double x) { return cost(r, x); }, t0 - span, t0 + span);
  }
  // A repeatability far below what the image resolves cannot be measured: the likelihood is flat
  // down to zero there and its maximum runs off to it, which would make the prior rigid. Each
  // variance is kept at least at the resolution of a variance estimate from these views: sqrt(2 /
  // (3 m)) times the image's own variance on its best-resolved axis (median over the views).
  const double m = static_cast<double>(deviations.size());
  std::vector<double> rotation_floor, translation_floor;
  for (const Deviation& d : deviations) {
    rotation_floor.push_back(
        Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(d.image_covariance.topLeftCorner<3, 3>()).eigenvalues()(0));
    translation_floor.push_back(
        Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(d.image_covariance.bottomRightCorner<3, 3>()).eigenvalues()(0));
  }
  const double resolution = std::sqrt(2 / (3 * m));
  r = std::max(r, std::log(resolution * std::max(median_in_place(rotation_floor), 1e-300)));
  t = std::max(t, std::log(resolution * std::max(median_in_place(translation_floor), 1e-300)));
  // The model's 12 fitted offsets take up part of the scatter.
  const double correction = 6 * m / (6 * m - 12);
  return {std::sqrt(3 * std::exp(t) * correction), std::sqrt(3 * std::exp(r) * correction) / kDegree};
}

// One view's image pose against the model's prediction, whitened by the covariance of their
// difference (image and robot).
struct DeviationResidual {
  const DeclaredSetup* setup;
  panda::Joints q;
  Rigid T_camera_holder;
  Matrix6 whitening;

  bool operator()(const double* base, const double* mount, double* r) const {
    EffectParameters p;
    std::copy(base, base + 6, p.base);
    std::copy(mount, mount + 6, p.mount);
    Eigen::Map<Vector6> out(r);
    out = whitening * flange_deviation(*setup, p, q, T_camera_holder);
    return true;
  }
};

struct WeakOffsetPrior {
  template <typename T>
  bool operator()(const T* base, const T* mount, T* r) const {
    for (int i = 0; i < 6; ++i) {
      const double sigma = i < 3 ? 5 * kDegree : 20.0;
      r[i] = base[i] / sigma;
      r[6 + i] = mount[i] / sigma;
    }
    return true;
  }
};

// The robot's base and mount offsets that best explain the image poses of `views`.
EffectParameters fit_robot_model(const ScanObservations& o, const std::vector<std::size_t>& views,
                                 const std::vector<Matrix6>& image_covariance, const Matrix6& prior_covariance,
                                 const EffectParameters& start) {
  EffectParameters p = start;
  ceres::Problem problem;
  for (std::size_t i : views) {
    const Eigen::LLT<Matrix6> llt(image_covariance[i] + prior_covariance);
    const Matrix6 whitening = llt.matrixL().solve(Matrix6::Identity());  // L^-1: |L^-1 n|^2 = n' (LL')^-1 n
    auto* f = new DeviationResidual{&o.setup, *o.views[i].joints, o.views[i].T_calibrated, whitening};
    problem.AddResidualBlock(new ceres::NumericDiffCostFunction<DeviationResidual, ceres::CENTRAL, 6, 6, 6>(f), nullptr, p.base,
                             p.mount);
  }
  // Base and mount trade off against each other along directions the trajectory does not turn
  // (on a joint-7 orbit, a shift along the axis in one is one in the other): a weak prior (20 mm,
  // 5 deg, far beyond any setup's error) keeps the smallest pair among equivalent ones.
  problem.AddResidualBlock(new ceres::AutoDiffCostFunction<WeakOffsetPrior, 12, 6, 6>(new WeakOffsetPrior), nullptr, p.base,
                           p.mount);
  solve_small_problem(problem, 50, 1e-10);
  return p;
}

// Fits the model with the repeatability assumed, measures the repeatability about it, refits
// (four rounds). Views whose image and robot disagree beyond both noises (p < 0.001) take no part
// in either. False (with the reason in `result`) when too few views agree.
bool measure_repeatability_and_consistency(const ScanObservations& o, const std::vector<std::size_t>& views,
                                           const std::vector<Matrix6>& image_covariance, const RobotPriorOptions& options,
                                           Repeatability& repeatability, std::vector<std::size_t>& consistent,
                                           EffectParameters& model, RobotPriorFit& result) {
  for (int round = 0; round < 4; ++round) {
    const Matrix6 prior_covariance = prior_information(repeatability).inverse();
    model = fit_robot_model(o, consistent, image_covariance, prior_covariance, model);
    std::vector<Deviation> deviations(o.views.size()), of_consistent;
    for (std::size_t i : views)
      deviations[i] = {flange_deviation(o.setup, model, *o.views[i].joints, o.views[i].T_calibrated), image_covariance[i]};
    for (std::size_t i : consistent) of_consistent.push_back(deviations[i]);
    repeatability = measure_repeatability(of_consistent, repeatability);
    const Matrix6 measured = prior_information(repeatability).inverse();
    consistent.clear();
    result.inconsistent_views.clear();
    for (std::size_t i : views) {
      const Deviation& d = deviations[i];
      if (d.n.dot((d.image_covariance + measured).ldlt().solve(d.n)) <= kConsistent)
        consistent.push_back(i);
      else
        result.inconsistent_views.push_back(o.views[i].view);
    }
    if (static_cast<int>(consistent.size()) < options.min_views) {
      result.reason = "only " + std::to_string(consistent.size()) + " views agree with the robot's model";
      return false;
    }
  }
  return true;
}

// One view's combined pose `T` written into the calibration: its matrix, residuals and pose
// uncertainty (image and prior). Returns its rotation uncertainty from the image alone and combined.
std::pair<double, double> combine_view(const ScanDescription& scan, const ScanObservations& o, const EffectParameters& model,
                                       const Matrix6& prior, const ViewObservations& v, const Rigid& T, ScanCalibration& c) {
  ViewCalibration& out = c.views[static_cast<std::size_t>(v.view)];
  const FlangeChain chain = flange_chain(o.setup, model, *v.joints);
  const Vector6 n = flange_deviation(o.setup, model, *v.joints, T);
  const Matrix6 image = image_information(o, v, chain, n);
  const Matrix6 covariance = (image + prior).inverse();
  const double image_sigma = rotation_sigma_deg(chain, image.inverse());
  // The holder origin's uncertainty in camera axes.
  Eigen::Matrix<double, 3, 6> G;
  for (int q = 0; q < 6; ++q) {
    Vector6 d = Vector6::Zero();
    d(q) = 1e-6;
    G.col(q) = (perturbed(chain, n, d).translation() - perturbed(chain, n, -d).translation()) / 2e-6;
  }
  const Eigen::Matrix3d origin = G * covariance * G.transpose();
  for (int a = 0; a < 3; ++a) out.translation_sigma_mm[a] = std::sqrt(origin(a, a));
  out.rotation_sigma_deg = rotation_sigma_deg(chain, covariance);

  out.T_camera_holder = T;
  out.P = view_camera(scan, v.view).P(T);
  double sq = 0;
  for (std::size_t k = 0; k < out.spheres.size(); ++k) {
    out.fitted_px[k] = out.P->project(scan.holder->spheres_mm[static_cast<std::size_t>(out.spheres[k])]);
    sq += (out.detected_px[k] - out.fitted_px[k]).squaredNorm();
  }
  out.rms_px = out.spheres.empty() ? 0.0 : std::sqrt(sq / static_cast<double>(out.spheres.size()));
  GeometryView& g = c.geometry.views[static_cast<std::size_t>(v.view)];
  g.P = out.P;
  g.rms_px = out.rms_px;
  return {image_sigma, out.rotation_sigma_deg};
}

}  // namespace

void RobotPriorOptions::validate() const {
  require_option(min_views >= 12, "RobotPriorOptions.min_views", "at least 12 (the model has 12 offsets)", min_views);
  require_option(start_sigma_mm > 0, "RobotPriorOptions.start_sigma_mm", "a number above 0", start_sigma_mm);
  require_option(start_sigma_deg > 0, "RobotPriorOptions.start_sigma_deg", "a number above 0", start_sigma_deg);
}

RobotPriorFit combine_with_robot(const ScanDescription& scan, ScanCalibration& c, const RobotPriorOptions& options) {
  options.validate();
  RobotPriorFit result;
  if (!scan.panda) {
    result.reason = "the poses do not come from a robot";
    return result;
  }
  ScanObservations o = observe_calibration(scan, c);
  std::vector<std::size_t> views;
  for (std::size_t i = 0; i < o.views.size(); ++i)
    if (o.views[i].joints) views.push_back(i);
  if (static_cast<int>(views.size()) < options.min_views) {
    result.reason = std::to_string(views.size()) + " calibrated views with joints; the robot's model needs " +
                    std::to_string(options.min_views);
    return result;
  }
  // A view whose spheres fit worse than the others' (overlaps, a sample's edge) is trusted less.
  for (ViewObservations& v : o.views) {
    const ViewCalibration& r = c.views[static_cast<std::size_t>(v.view)];
    const int dof = 2 * static_cast<int>(r.spheres.size()) - 6;
    if (dof > 0)
      v.centre_sigma_px = std::max(o.centre_sigma_px, r.rms_px * std::sqrt(r.spheres.size() / static_cast<double>(dof)));
  }
  // Each view's image pose is summarised by its deviation from the model and the image's
  // covariance of it (the poses eliminated: exact for Gaussian noise to first order, and a scan
  // of 360 views costs a 12-parameter fit instead of a bundle adjustment).
  std::vector<Matrix6> image_covariance(o.views.size());
  const EffectParameters declared;
  for (std::size_t i : views) {
    const ViewObservations& v = o.views[i];
    const FlangeChain chain = flange_chain(o.setup, declared, *v.joints);
    image_covariance[i] =
        image_information(o, v, chain, flange_deviation(o.setup, declared, *v.joints, v.T_calibrated)).inverse();
  }
  Repeatability repeatability{options.start_sigma_mm, options.start_sigma_deg};
  std::vector<std::size_t> consistent = views;
  EffectParameters model;
  if (!measure_repeatability_and_consistency(o, views, image_covariance, options, repeatability, consistent, model, result))
    return result;
  model = fit_robot_model(o, consistent, image_covariance, prior_information(repeatability).inverse(), model);
  // Every view, the model fixed: its pose from its spheres and the prior.
  o.robot_sigma_mm = repeatability.sigma_mm;
  o.robot_sigma_deg = repeatability.sigma_deg;
  const ScanModelFit combined = fit_view_poses(o, model, views);

  std::vector<double> image_sigma, combined_sigma;
  const Matrix6 prior = prior_information(repeatability);
  for (std::size_t slot = 0; slot < views.size(); ++slot) {
    const ViewObservations& v = o.views[views[slot]];
    const auto [image, combined_view] = combine_view(scan, o, model, prior, v, combined.poses[slot], c);
    image_sigma.push_back(image);
    combined_sigma.push_back(combined_view);
  }
  result.applied = true;
  result.views = static_cast<int>(views.size());
  result.sigma_mm = repeatability.sigma_mm;
  result.sigma_deg = repeatability.sigma_deg;
  result.model = model;
  result.image_rotation_sigma_deg = median(image_sigma);
  result.combined_rotation_sigma_deg = median(combined_sigma);
  return result;
}

}  // namespace ctk

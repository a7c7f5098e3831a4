#include "ctk/calib/residual_structure.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <sstream>

#include "ctk/core/statistics.hpp"
#include "ctk/geom/panda.hpp"

namespace ctk {

namespace {

constexpr double kDegree = M_PI / 180.0;

// The fraction of deviation component c's variance that a linear fit on the direction of gravity
// in the flange frame explains (a load the model lacks: a sagging holder, a bending arm).
double gravity_explained(const ScanObservations& o, const std::vector<Eigen::Matrix<double, 6, 1>>& d, int c) {
  Eigen::MatrixXd A(static_cast<Eigen::Index>(d.size()), 4);
  Eigen::VectorXd y(static_cast<Eigen::Index>(d.size()));
  Eigen::Index row = 0;
  for (const auto& view : o.views) {
    if (!view.joints) continue;
    const Eigen::Vector3d g = panda::forward_kinematics(*view.joints).linear().transpose() * Eigen::Vector3d(0, 0, -1);
    A.row(row) << 1.0, g.x(), g.y(), g.z();
    y(row) = d[static_cast<std::size_t>(row)](c);
    ++row;
  }
  const Eigen::VectorXd fit = A * A.colPivHouseholderQr().solve(y);
  const double total = (y.array() - y.mean()).square().sum(), left = (y - fit).squaredNorm();
  return total > 0 ? 1 - left / total : 0;
}

// Said when the gravity fit explains most of component c.
std::string gravity_note(const ScanObservations& o, const std::vector<Eigen::Matrix<double, 6, 1>>& d, int c) {
  const double explained = gravity_explained(o, d, c);
  if (explained < 0.5) return "";
  std::ostringstream s;
  s << "; " << static_cast<int>(100 * explained) << " % of it follows the direction of gravity in the flange frame "
    << "(a load-dependent effect outside the vocabulary, such as the holder sagging)";
  return s.str();
}

// The residuals' noise per component (robust), and each residual clipped at 3 of it: a few
// detections biased by the scene (a sphere crossing the holder wall's edge, an overlap) must not
// make a group stand out, while a systematic error shifts every member of its group a little and
// survives the clip.
struct ResidualNoise {
  double sigma = 0;
  double clipped_variance = 0;  // of a component clipped at 3 sigma: 0.973 sigma^2 under Gaussian noise
  Eigen::Vector2d clipped(const Eigen::Vector2d& r) const {
    return Eigen::Vector2d(std::clamp(r.x(), -3 * sigma, 3 * sigma), std::clamp(r.y(), -3 * sigma, 3 * sigma));
  }
};

// Mean residual per sphere and per detector cell.
void group_structure(const ScanObservations& o, const ScanModelFit& f, const ResidualNoise& noise,
                     std::vector<StructureFinding>& out) {
  // Mean residual vectors in groups; chi-square with 2 dof against a Bonferroni threshold.
  auto test_groups = [&](const std::string& where, int groups, auto&& group_of, auto&& name_of) {
    std::vector<Eigen::Vector2d> sum(static_cast<std::size_t>(groups), Eigen::Vector2d::Zero());
    std::vector<int> count(static_cast<std::size_t>(groups), 0);
    for (std::size_t i = 0; i < o.views.size(); ++i)
      for (std::size_t k = 0; k < f.residual_px[i].size(); ++k) {
        const int g = group_of(i, k);
        if (g < 0) continue;
        sum[static_cast<std::size_t>(g)] += noise.clipped(f.residual_px[i][k]);
        ++count[static_cast<std::size_t>(g)];
      }
    const double threshold = -2.0 * std::log(1e-3 / groups);
    std::ostringstream what;
    int flagged = 0;
    for (int g = 0; g < groups; ++g) {
      const auto n = count[static_cast<std::size_t>(g)];
      if (n < 5) continue;
      const Eigen::Vector2d mean = sum[static_cast<std::size_t>(g)] / n;
      const double chi2 = n * mean.squaredNorm() / noise.clipped_variance;
      if (chi2 > threshold) {
        if (flagged < 6) what << (flagged ? "; " : "") << name_of(g) << " mean " << mean.norm() << " px over " << n;
        ++flagged;
      }
    }
    if (flagged) {
      std::ostringstream s;
      s << flagged << " of " << groups << " with a mean residual beyond noise (" << what.str() << (flagged > 6 ? "; ..." : "")
        << ")";
      out.push_back({where, s.str()});
    }
  };
  const auto spheres = static_cast<int>(o.setup.holder.spheres_mm.size());
  test_groups(
      "by sphere", spheres, [&](std::size_t i, std::size_t k) { return o.views[i].spheres[k]; },
      [](int g) { return "sphere " + std::to_string(g); });
  constexpr int kCells = 6;
  test_groups(
      "by detector region", kCells * kCells,
      [&](std::size_t i, std::size_t k) {
        const Eigen::Vector2d& m = o.views[i].measured_px[k];
        const int cu = std::clamp(static_cast<int>(m.x() / o.setup.detector.cols * kCells), 0, kCells - 1);
        const int cv = std::clamp(static_cast<int>(m.y() / o.setup.detector.rows * kCells), 0, kCells - 1);
        return cv * kCells + cu;
      },
      [](int g) { return "cell (" + std::to_string(g % kCells) + ", " + std::to_string(g / kCells) + ")"; });
}

// A sphere that moves during the scan: its residuals in view v follow J_v (a + b tau_v), J_v the
// projection's derivative with respect to the sphere's place, tau_v the scan's progress (-1/2 ..
// 1/2); a fitted place leaves a = 0, a move leaves b. Least squares for (a, b) and the chi-square
// that b explains (3 dof), Bonferroni over the spheres.
void moving_spheres(const ScanObservations& o, const ScanModelFit& f, const ResidualNoise& noise,
                    std::vector<StructureFinding>& out) {
  const auto spheres = static_cast<int>(o.setup.holder.spheres_mm.size());
  std::vector<Eigen::Matrix<double, 6, 6>> normal(static_cast<std::size_t>(spheres), Eigen::Matrix<double, 6, 6>::Zero());
  std::vector<Eigen::Matrix<double, 6, 1>> rhs(static_cast<std::size_t>(spheres), Eigen::Matrix<double, 6, 1>::Zero());
  std::vector<int> seen(static_cast<std::size_t>(spheres), 0);
  int first = o.views.front().view, last = first;
  for (const auto& v : o.views) first = std::min(first, v.view), last = std::max(last, v.view);
  const double span = std::max(1, last - first);
  for (std::size_t i = 0; i < o.views.size(); ++i) {
    const ViewObservations& view = o.views[i];
    const double tau = (view.view - first) / span - 0.5;
    for (std::size_t k = 0; k < view.spheres.size(); ++k) {
      const auto id = static_cast<std::size_t>(view.spheres[k]);
      const Eigen::Vector3d Y = f.poses[i] * (o.setup.holder.spheres_mm[id] + f.parameters.spheres[id]);
      Eigen::Matrix<double, 2, 3> dp;
      dp << o.setup.K.fu_px / Y.z(), o.setup.K.skew_px / Y.z(),
          -(o.setup.K.fu_px * Y.x() + o.setup.K.skew_px * Y.y()) / (Y.z() * Y.z()), 0, o.setup.K.fv_px / Y.z(),
          -o.setup.K.fv_px * Y.y() / (Y.z() * Y.z());
      const Eigen::Matrix<double, 2, 3> J = dp * f.poses[i].linear();
      Eigen::Matrix<double, 2, 6> A;
      A << J, tau * J;
      normal[id] += A.transpose() * A;
      rhs[id] += A.transpose() * noise.clipped(f.residual_px[i][k]);
      ++seen[id];
    }
  }
  const double chi2_3 = 3 * std::pow(1 - 2 / 27.0 + 4.75 * std::sqrt(2 / 27.0), 3);  // p ~ 1e-6 (Wilson-Hilferty)
  const double threshold = chi2_3 + 2 * std::log(static_cast<double>(spheres));      // and for the number of spheres
  std::ostringstream what;
  int flagged = 0;
  for (int k = 0; k < spheres; ++k) {
    const auto id = static_cast<std::size_t>(k);
    if (seen[id] < 10) continue;
    const Eigen::Matrix<double, 6, 6>& N = normal[id];
    // The move's part: the chi-square of b after a is fitted (Schur complement of a's block).
    const Eigen::Matrix3d Naa = N.topLeftCorner<3, 3>(), Nab = N.topRightCorner<3, 3>(), Nbb = N.bottomRightCorner<3, 3>();
    const Eigen::Matrix3d S = Nbb - Nab.transpose() * Naa.completeOrthogonalDecomposition().pseudoInverse() * Nab;
    const Eigen::Vector3d g =
        rhs[id].tail<3>() - Nab.transpose() * Naa.completeOrthogonalDecomposition().pseudoInverse() * rhs[id].head<3>();
    const Eigen::Vector3d b = S.completeOrthogonalDecomposition().solve(g);
    const double chi2 = g.dot(b) / noise.clipped_variance;
    if (chi2 > threshold) {
      if (flagged < 6) what << (flagged ? "; " : "") << "sphere " << k << " moves " << b.norm() << " mm over the scan";
      ++flagged;
    }
  }
  if (flagged) {
    std::ostringstream s;
    s << flagged << " of " << spheres << " spheres whose residuals follow the scan's progress (" << what.str()
      << (flagged > 6 ? "; ..." : "") << "): a place that changes during the scan, outside the vocabulary";
    out.push_back({"by sphere over the scan", s.str()});
  }
}

void robot_channel_structure(const ScanObservations& o, const ScanModelFit& f, std::vector<StructureFinding>& out) {
  // The robot channel: each view's pose relative to the model's prediction, in units of the
  // repeatability. Independent noise has no memory from one view to the next and a mean square of
  // about 1 per component; a slowly varying unmodelled effect has both.
  if (o.setup.robot) {
    std::vector<Eigen::Matrix<double, 6, 1>> d;
    std::vector<Eigen::Vector3d> moved;  // the holder origin's deviation in the camera frame (mm)
    for (std::size_t i = 0; i < o.views.size(); ++i) {
      if (!o.views[i].joints) continue;
      const Rigid predicted = robot_predicted_pose(o.setup, f.parameters, *o.views[i].joints);
      // At the flange, where the repeatability acts: at the holder's origin a flange turn adds its
      // lever arm's shift, and the translation there spreads more than the repeatability says
      // (1.5 times at 0.02 mm and 0.005 deg, which flagged every such scan "beyond").
      Eigen::Matrix<double, 6, 1> x = flange_deviation(o.setup, f.parameters, *o.views[i].joints, f.poses[i]);
      x.head<3>() /= o.robot_sigma_deg * kDegree / std::sqrt(3.0);
      x.tail<3>() /= o.robot_sigma_mm / std::sqrt(3.0);
      d.push_back(x);
      moved.push_back(f.poses[i].translation() - predicted.translation());
    }
    const auto n = static_cast<double>(d.size());
    if (n >= 20) {
      // Lag-1 correlation of a series in view order; scale-free, so the noise's size does not matter.
      auto smooth = [&](auto&& component, const std::string& what) {
        double mean = 0, var = 0, lag = 0;
        for (std::size_t i = 0; i < d.size(); ++i) mean += component(i) / n;
        for (std::size_t i = 0; i < d.size(); ++i) var += (component(i) - mean) * (component(i) - mean) / n;
        for (std::size_t i = 1; i < d.size(); ++i) lag += (component(i) - mean) * (component(i - 1) - mean) / n;
        const double r = var > 0 ? lag / var : 0;
        if (r * std::sqrt(n) > 4.0) {
          std::ostringstream s;
          s << what << " changes smoothly from view to view (lag-1 correlation " << r << ", noise would give |r| < "
            << 4.0 / std::sqrt(n) << ")";
          out.push_back({"by view order", s.str()});
        }
      };
      // In the flange's frame (a slowly bending arm or holder) and in the camera's (what moves with
      // time in the lab: the focal spot, the detector), whatever the trajectory's order of directions.
      for (int c = 0; c < 6; ++c)
        smooth([&](std::size_t i) { return d[i](c); }, std::string("the pose's deviation from the robot model (") +
                                                           (c < 3 ? "rotation " : "translation ") + "xyz"[c % 3] +
                                                           ", flange frame)");
      for (int c = 0; c < 3; ++c)
        smooth([&](std::size_t i) { return moved[i](c); },
               std::string("the holder's place against the robot model's (") + "xyz"[c] + ", camera frame)");
      // Independent of the order and of the noise's scale: a load-dependent deviation follows the
      // direction of gravity in the flange frame. n R^2 of the fit on it is chi-square with 3 dof
      // under noise (Lagrange multiplier test); threshold at p ~ 1e-6 per component. This holds
      // whatever the repeatability is, measured or stated.
      const double chi2_3 = 3 * std::pow(1 - 2 / 27.0 + 4.75 * std::sqrt(2 / 27.0), 3);
      for (int c = 0; c < 6; ++c) {
        const double explained = gravity_explained(o, d, c);
        if (n * explained > chi2_3) {
          std::ostringstream s;
          s << "the pose's deviation from the robot model (" << (c < 3 ? "rotation " : "translation ") << "xyz"[c % 3]
            << ") follows the "
            << "direction of gravity in the flange frame (" << static_cast<int>(100 * explained)
            << " % of its variance; noise would "
            << "explain under " << std::max(1, static_cast<int>(100 * chi2_3 / n))
            << " %): a load-dependent effect outside the vocabulary, "
            << "such as the holder sagging";
          out.push_back({"by robot configuration", s.str()});
        }
      }
      // Independent of the order: deviations larger than the repeatability allows (the per-view
      // pose leans on the robot prior, so the model's own deviations are smaller than that).
      // Chi-square with n dof per component (Wilson-Hilferty), p ~ 1e-5 each.
      const double limit = n * std::pow(1 - 2 / (9 * n) + 4.3 * std::sqrt(2 / (9 * n)), 3);
      for (int c = 0; c < 6; ++c) {
        double sum2 = 0;
        for (const auto& x : d) sum2 += x(c) * x(c);
        if (sum2 > limit) {
          std::ostringstream s;
          s << "the pose's deviation from the robot model (" << (c < 3 ? "rotation " : "translation ") << "xyz"[c % 3] << ") is "
            << std::sqrt(sum2 / n) << " times the repeatability (RMS), beyond what it allows (" << std::sqrt(limit / n) << ")"
            << gravity_note(o, d, c);
          out.push_back({"by robot configuration", s.str()});
        }
      }
    }
  }
}

}  // namespace

// Residual structure the final model leaves, tested against the noise (Bonferroni over the groups).
std::vector<StructureFinding> find_structure(const ScanObservations& o, const ScanModelFit& f) {
  std::vector<StructureFinding> out;
  std::vector<double> components;
  for (const auto& view : f.residual_px)
    for (const auto& r : view) {
      components.push_back(std::abs(r.x()));
      components.push_back(std::abs(r.y()));
    }
  if (components.size() < 20) return out;
  const double sigma = 1.4826 * median_in_place(components);
  const ResidualNoise noise{sigma, 0.973 * sigma * sigma};
  group_structure(o, f, noise, out);
  moving_spheres(o, f, noise, out);
  robot_channel_structure(o, f, out);
  return out;
}

}  // namespace ctk

#include "ctk/recon/fdk.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <numeric>
#include <opencv2/core.hpp>
#include <sstream>
#include <stdexcept>

#include "ctk/core/parallel.hpp"
#include "ctk/proj/voxel_backprojection.hpp"

namespace ctk {

namespace {

constexpr double kTwoPi = 2 * M_PI;

double wrap_2pi(double a) {
  a = std::fmod(a, kTwoPi);
  return a < 0 ? a + kTwoPi : a;
}

// Ram-Lak kernel sampled at spacing `da` (mm), as its DFT over `n` points (real, even), with an
// optional Hann window: h[0] = 1 / (4 da^2), h[odd k] = -1 / (pi k da)^2, h[even k] = 0.
std::vector<float> ramp_filter_spectrum(int n, double da, RampWindow window) {
  cv::Mat kernel(1, n, CV_32F, cv::Scalar(0));
  for (int k = 0; k < n; ++k) {
    const int m = std::min(k, n - k);
    double h = 0;
    if (m == 0)
      h = 1.0 / (4 * da * da);
    else if (m % 2 == 1)
      h = -1.0 / (M_PI * M_PI * m * m * da * da);
    kernel.at<float>(0, k) = static_cast<float>(h * da);  // times da: the convolution's measure
  }
  cv::Mat spectrum;
  cv::dft(kernel, spectrum, cv::DFT_COMPLEX_OUTPUT);
  std::vector<float> gain(static_cast<std::size_t>(n));
  for (int k = 0; k < n; ++k) {
    const double frequency = static_cast<double>(std::min(k, n - k)) / n;  // cycles per sample, 0 .. 0.5
    const double w = window == RampWindow::hann ? 0.5 * (1 + std::cos(2 * M_PI * frequency)) : 1.0;
    gain[static_cast<std::size_t>(k)] = static_cast<float>(spectrum.at<cv::Vec2f>(0, k)[0] * w);
  }
  return gain;
}

}  // namespace

CircularTrajectory fit_circular_trajectory(const std::vector<ProjectionMatrix>& views) {
  if (views.size() < 3) throw std::invalid_argument("FDK needs at least 3 views");
  std::vector<Eigen::Vector3d> s;
  s.reserve(views.size());
  for (const auto& P : views) s.push_back(P.source_position());
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (const auto& p : s) mean += p;
  mean /= static_cast<double>(s.size());
  Eigen::Matrix3d scatter = Eigen::Matrix3d::Zero();
  for (const auto& p : s) scatter += (p - mean) * (p - mean).transpose();
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(scatter);
  CircularTrajectory c;
  c.axis = eig.eigenvectors().col(0);
  // Orient the axis so that the views turn positively about it (first to second view).
  const Eigen::Vector3d e1 = eig.eigenvectors().col(2), e2 = c.axis.cross(e1);
  // Circle in the plane: algebraic (Kasa) fit x^2 + y^2 + D x + E y + F = 0.
  Eigen::MatrixXd M(static_cast<Eigen::Index>(s.size()), 3);
  Eigen::VectorXd rhs(static_cast<Eigen::Index>(s.size()));
  for (std::size_t i = 0; i < s.size(); ++i) {
    const double x = (s[i] - mean).dot(e1), y = (s[i] - mean).dot(e2);
    M.row(static_cast<Eigen::Index>(i)) << x, y, 1;
    rhs(static_cast<Eigen::Index>(i)) = -(x * x + y * y);
  }
  const Eigen::Vector3d def = M.colPivHouseholderQr().solve(rhs);
  const double cx = -def(0) / 2, cy = -def(1) / 2;
  c.centre = mean + cx * e1 + cy * e2;
  c.radius_mm = std::sqrt(std::max(0.0, cx * cx + cy * cy - def(2)));
  for (const auto& p : s) {
    c.off_plane_mm = std::max(c.off_plane_mm, std::abs((p - mean).dot(c.axis)));
    const Eigen::Vector3d in_plane = (p - c.centre) - (p - c.centre).dot(c.axis) * c.axis;
    c.off_circle_mm = std::max(c.off_circle_mm, std::abs(in_plane.norm() - c.radius_mm));
  }
  const double tolerance = std::max(1.0, 0.002 * c.radius_mm);
  if (!(c.radius_mm > 0) || c.off_plane_mm > tolerance || c.off_circle_mm > tolerance) {
    std::ostringstream what;
    what << "FDK needs a circular trajectory: the sources are up to " << c.off_plane_mm << " mm off their best plane and "
         << c.off_circle_mm << " mm off the best circle (radius " << c.radius_mm << " mm; tolerance " << tolerance
         << " mm); use an iterative method (wls-cg or sirt) for this scan";
    throw std::invalid_argument(what.str());
  }
  auto angle_of = [&](const Eigen::Vector3d& p) { return std::atan2((p - c.centre).dot(e2), (p - c.centre).dot(e1)); };
  if (wrap_2pi(angle_of(s[1]) - angle_of(s[0])) > M_PI) c.axis = -c.axis;
  const Eigen::Vector3d f1 = e1, f2 = c.axis.cross(f1);
  auto angle = [&](const Eigen::Vector3d& p) { return std::atan2((p - c.centre).dot(f2), (p - c.centre).dot(f1)); };
  const double a0 = angle(s[0]);
  for (const auto& p : s) c.angles_rad.push_back(wrap_2pi(angle(p) - a0));

  // Covered arc: a full turn minus the largest gap between neighbouring views, when that gap is
  // clearly larger than the typical step; each view weighs half the gaps to its neighbours.
  std::vector<std::size_t> order(s.size());
  std::iota(order.begin(), order.end(), 0);
  std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return c.angles_rad[a] < c.angles_rad[b]; });
  const std::size_t n = order.size();
  std::vector<double> gap_after(n);
  for (std::size_t i = 0; i < n; ++i) gap_after[i] = wrap_2pi(c.angles_rad[order[(i + 1) % n]] - c.angles_rad[order[i]]);
  const std::size_t widest = static_cast<std::size_t>(std::max_element(gap_after.begin(), gap_after.end()) - gap_after.begin());
  const double typical = kTwoPi / static_cast<double>(n);
  const bool full_turn = gap_after[widest] < 1.5 * typical;
  c.arc_rad = full_turn ? kTwoPi : kTwoPi - gap_after[widest];
  c.step_rad.assign(n, 0.0);
  for (std::size_t i = 0; i < n; ++i) {
    const double before = gap_after[(i + n - 1) % n], after = gap_after[i];
    double w = 0.5 * (before + after);
    if (!full_turn && i == widest) w = 0.5 * before;               // last view of the arc
    if (!full_turn && (i + n - 1) % n == widest) w = 0.5 * after;  // first view of the arc
    c.step_rad[order[i]] = w;
  }
  if (!full_turn) {
    // Angles measured from the start of the arc (the view after the widest gap).
    const double start = c.angles_rad[order[(widest + 1) % n]];
    for (double& a : c.angles_rad) a = wrap_2pi(a - start);
  }
  return c;
}

double parker_weight(double beta, double gamma, double arc) {
  const double delta = 0.5 * (arc - M_PI);
  if (beta < 0 || beta > arc) return 0.0;
  if (beta < 2 * (delta - gamma)) {
    const double s = std::sin(M_PI / 4 * beta / (delta - gamma));
    return s * s;
  }
  if (beta <= M_PI - 2 * gamma) return 1.0;
  const double s = std::sin(M_PI / 4 * (M_PI + 2 * delta - beta) / (delta + gamma));
  return s * s;
}

void fdk_reconstruct(const std::vector<ProjectionMatrix>& views, ProjectionStack& b, const Detector& detector, Volume& x,
                     RampWindow window) {
  const CircularTrajectory c = fit_circular_trajectory(views);
  const bool full_turn = c.arc_rad >= kTwoPi - 1e-9;
  const int cols = b.cols, rows = b.rows;
  const int n_fft = cv::getOptimalDFTSize(2 * cols);

  // Views are filtered independently: a few at a time.
  parallel_for_dynamic(static_cast<int>(views.size()), [&](int view) {
    const auto v = static_cast<std::size_t>(view);
    const ProjectionMatrix& P = views[v];
    const Eigen::Vector3d source = P.source_position();
    const Eigen::Vector3d central = (c.centre - source - (c.centre - source).dot(c.axis) * c.axis).normalized();
    const Eigen::Vector3d principal = P.principal_ray();
    // The axis must run along v: rows are the filter lines.
    const Eigen::Vector2d a0 = P.project(c.centre), a1 = P.project(c.centre + 10 * c.axis);
    const double tilt = std::atan2(std::abs((a1 - a0).x()), std::abs((a1 - a0).y()));
    if (tilt > 5 * M_PI / 180)
      throw std::invalid_argument("FDK filters along detector rows, but the rotation axis appears " +
                                  std::to_string(tilt * 180 / M_PI) + " deg from the detector's v direction in view " +
                                  std::to_string(v) + "; use an iterative method");
    // Sample spacing on a virtual detector through the axis: the pixel pitch demagnified.
    const double sdd = detector.pitch_u_mm * P.decompose().intrinsics.fu_px;
    const double da = detector.pitch_u_mm * c.radius_mm / std::abs(sdd);
    const std::vector<float> gain = ramp_filter_spectrum(n_fft, da, window);

    // Pixel rays: M^-1 (u, v, 1) has depth 1 along the principal ray (P is normalised), so it
    // points away from the source; inverted once per view, not per pixel.
    const Eigen::Matrix3d M_inverse = P.matrix().leftCols<3>().inverse();
    cv::Mat padded(rows, n_fft, CV_32F, cv::Scalar(0));
    for (int r = 0; r < rows; ++r)
      for (int col = 0; col < cols; ++col) {
        const Eigen::Vector3d ray = (M_inverse * Eigen::Vector3d(col, r, 1.0)).normalized();
        // Cosine pre-weight; redundancy weight (1/2 for a full turn, Parker otherwise).
        double w = std::abs(ray.dot(principal));
        if (full_turn) {
          w *= 0.5;
        } else {
          const Eigen::Vector3d flat = (ray - ray.dot(c.axis) * c.axis).normalized();
          const double gamma = std::atan2(central.cross(flat).dot(c.axis), central.dot(flat));
          w *= parker_weight(c.angles_rad[v], gamma, c.arc_rad);
        }
        padded.at<float>(r, col) = static_cast<float>(w * b.at(static_cast<int>(v), r, col));
      }
    cv::Mat spectrum;
    cv::dft(padded, spectrum, cv::DFT_ROWS | cv::DFT_COMPLEX_OUTPUT);
    for (int r = 0; r < rows; ++r)
      for (int k = 0; k < n_fft; ++k) spectrum.at<cv::Vec2f>(r, k) *= gain[static_cast<std::size_t>(k)];
    cv::Mat filtered;
    cv::dft(spectrum, filtered, cv::DFT_ROWS | cv::DFT_INVERSE | cv::DFT_SCALE | cv::DFT_REAL_OUTPUT);
    for (int r = 0; r < rows; ++r)
      for (int col = 0; col < cols; ++col)
        b.at(static_cast<int>(v), r, col) = filtered.at<float>(r, col) * static_cast<float>(c.step_rad[v]);
  });

  // Voxel-driven back projection, weighted by (R / depth)^2.
  voxel_backproject(b, views, c.radius_mm, x);
}

}  // namespace ctk

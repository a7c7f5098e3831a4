#include "ctk/calib/view_calibration.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "ctk/calib/pose_fit.hpp"
#include "ctk/calib/sphere_profile_fit.hpp"
#include "ctk/calib/sphere_matching.hpp"

namespace ctk {

namespace {

constexpr double kGrazingCosine = 0.3;  // |radial . ray| below: the sphere sits on the silhouette

struct Prediction {
  std::vector<Eigen::Vector2d> uv;
  std::vector<bool> usable;  // on the detector with room for the background ring, not overlapping
};

Prediction predict(const Eigen::Matrix3d& K, const Rigid& T, const Holder& holder, const Detector& detector, double radius_px) {
  Prediction p;
  std::vector<bool> visible;
  // The source in the holder frame: rays to spheres on the holder's silhouette graze the wall,
  // whose steep edge there defeats a planar background; those spheres are left out.
  const Eigen::Vector3d source = T.inverse().translation();
  for (const auto& X : holder.spheres_mm) {
    const Eigen::Vector3d c = K * (T * X);
    p.uv.push_back(c.head<2>() / c.z());
    const Eigen::Vector3d radial(X.x(), X.y(), 0), ray = (X - source).normalized();
    const bool grazing = radial.norm() > 0 && std::abs(radial.normalized().dot(ray)) < kGrazingCosine;
    visible.push_back(c.z() > 0 && detector.contains(p.uv.back(), radius_px + 6) && !grazing);
  }
  // Two spheres closer than this share pixels of their centroid windows: neither is used.
  const double apart = 2 * radius_px + 4;
  p.usable = visible;
  for (std::size_t i = 0; i < p.uv.size(); ++i)
    for (std::size_t j = i + 1; j < p.uv.size(); ++j)
      if ((p.uv[i] - p.uv[j]).norm() < apart) p.usable[i] = p.usable[j] = false;
  return p;
}

}  // namespace

ViewCalibration calibrate_view(const Image& image, const Eigen::Matrix3d& K, const Rigid& initial, const Holder& holder,
                               const Detector& detector, const CalibrationOptions& o, const std::optional<RadialDistortion>& distortion) {
  ViewCalibration out;
  // Projected sphere radius at the holder's depth.
  const double depth = (K.row(2) * initial.translation())(0);
  const double radius_px = 0.5 * holder.sphere_diameter_mm * K(0, 0) / std::max(depth, 1e-9);
  out.radius_px = radius_px;
  DetectionOptions detection;
  detection.radius_px = radius_px;
  // `measured` are where the centres are in the image (profile fits refine them there); `detections`
  // are the same centres where an ideal pinhole detector would have them (a declared distortion
  // removed), which is what matching and the pose fit compare with projections.
  std::vector<SphereDetection> measured = detect_spheres(image, detection);
  std::vector<SphereDetection> detections = measured;
  auto undistort = [&](std::size_t i) {
    detections[i].uv = distortion ? distortion->ideal_from_measured(measured[i].uv) : measured[i].uv;
  };
  for (std::size_t i = 0; i < detections.size(); ++i) undistort(i);
  out.detections = static_cast<int>(detections.size());

  // Each candidate shift of the predicted pattern is tried: match, fit, then match again from the
  // fitted pose with a tight gate and refit, then drop outliers and refit once.
  struct Attempt {
    std::vector<SphereMatch> matches;
    std::vector<SphereMatch> dropped;  // matched, but left out as outliers
    PoseFit fit;
  };
  auto fit_matches = [&](const Rigid& start, const std::vector<SphereMatch>& matches) {
    std::vector<Eigen::Vector3d> X;
    std::vector<Eigen::Vector2d> uv;
    for (const auto& m : matches) {
      X.push_back(holder.spheres_mm[static_cast<std::size_t>(m.sphere)]);
      uv.push_back(detections[static_cast<std::size_t>(m.detection)].uv);
    }
    return fit_pose(K, start, X, uv, o.robust_px);
  };
  const Prediction first = predict(K, initial, holder, detector, radius_px);
  auto attempt = [&](const Eigen::Vector2d& shift) {
    Attempt a;
    Rigid pose = initial;
    Eigen::Vector2d s = shift;
    double gate = 4.0;
    for (int round = 0; round < 3; ++round) {
      const Prediction p = round == 0 ? first : predict(K, pose, holder, detector, radius_px);
      a.matches = match_spheres(p.uv, p.usable, detections, s, gate);
      if (static_cast<int>(a.matches.size()) < o.min_spheres) return Attempt{};
      a.fit = fit_matches(pose, a.matches);
      pose = a.fit.T_camera_holder;
      s = Eigen::Vector2d::Zero();
      gate = 1.5;
    }
    // A uniform helix maps onto itself under a screw by one sphere (14.4 deg about its axis with a
    // slide along it): such a solution matches almost every sphere. The first guess tells them
    // apart, so a pose turned further from it than the guess can be wrong is refused.
    if (rotation_angle_deg(a.fit.T_camera_holder.linear() * initial.linear().transpose()) > o.max_first_guess_error_deg)
      return Attempt{};
    // Spheres whose centre a nearby edge of the sample has pulled (background not planar) leave
    // residuals far beyond the rest: drop those beyond 3 robust deviations (at least 0.25 px) and
    // refit once.
    std::vector<double> r = a.fit.residual_px;
    std::nth_element(r.begin(), r.begin() + static_cast<std::ptrdiff_t>(r.size() / 2), r.end());
    const double limit = std::max(0.25, 3 * 1.4826 * r[r.size() / 2]);
    std::vector<SphereMatch> kept, dropped;
    for (std::size_t i = 0; i < a.matches.size(); ++i) (a.fit.residual_px[i] <= limit ? kept : dropped).push_back(a.matches[i]);
    if (!dropped.empty() && static_cast<int>(kept.size()) >= o.min_spheres) {
      a.matches = std::move(kept);
      a.dropped = std::move(dropped);
      a.fit = fit_matches(pose, a.matches);
    }
    return a;
  };
  const int visible = static_cast<int>(std::count(first.usable.begin(), first.usable.end(), true));
  Attempt best = attempt(Eigen::Vector2d::Zero());
  const bool first_guess_holds = static_cast<int>(best.matches.size()) >= std::max(o.min_spheres, visible / 2) &&
                                 best.fit.rms_px <= o.max_rms_px;
  if (!first_guess_holds) {
    // Among the shifts, the one matching most spheres; near-ties (within 10 %) go to the lower RMS.
    for (const auto& shift : candidate_shifts(first.uv, first.usable, detections, o.search_px, 8)) {
      if (shift.norm() == 0) continue;
      Attempt a = attempt(shift);
      if (a.matches.empty()) continue;
      const double more = static_cast<double>(a.matches.size()), have = static_cast<double>(best.matches.size());
      if (more > 1.1 * have || (more >= 0.9 * have && a.fit.rms_px < best.fit.rms_px)) best = std::move(a);
    }
  }
  if (best.matches.empty()) {
    out.reason = "too few spheres: no consistent match of the " + std::to_string(out.detections) +
                 " detections near the first-guess pose (at least " + std::to_string(o.min_spheres) + " spheres needed)";
    return out;
  }
  // The matched spheres' centres from their whole profiles, then the final fit. A sphere whose
  // profile fit fails keeps its centroid.
  for (const auto* list : {&best.matches, &best.dropped})
    for (const auto& m : *list) {
      const auto i = static_cast<std::size_t>(m.detection);
      refine_by_profile_fit(image, radius_px, measured[i]);
      undistort(i);
    }
  best.fit = fit_matches(best.fit.T_camera_holder, best.matches);
  const std::vector<SphereMatch>& matches = best.matches;
  const PoseFit& fit = best.fit;
  out.spheres_used = static_cast<int>(matches.size());
  if (out.spheres_used < o.min_spheres) {
    out.reason = "too few spheres: " + std::to_string(out.spheres_used) + " matched of " + std::to_string(out.detections) +
                 " detected (at least " + std::to_string(o.min_spheres) + " needed)";
    return out;
  }
  out.rms_px = fit.rms_px;
  out.T_camera_holder = fit.T_camera_holder;
  out.P = ProjectionMatrix::compose(K, fit.T_camera_holder);
  for (int a = 0; a < 3; ++a) out.translation_sigma_mm[a] = fit.translation_sigma_mm[a];
  out.rotation_sigma_deg = fit.rotation_sigma_deg;
  for (const auto& m : matches) {
    out.spheres.push_back(m.sphere);
    out.detected_px.push_back(detections[static_cast<std::size_t>(m.detection)].uv);
    out.fitted_px.push_back(out.P->project(holder.spheres_mm[static_cast<std::size_t>(m.sphere)]));
  }
  for (const auto& m : best.dropped) {
    out.outlier_spheres.push_back(m.sphere);
    out.outlier_detected_px.push_back(detections[static_cast<std::size_t>(m.detection)].uv);
  }
  if (!fit.converged) {
    out.reason = "pose fit did not converge";
  } else if (fit.rms_px > o.max_rms_px) {
    std::ostringstream r;
    r << "residual above threshold: " << fit.rms_px << " px RMS over " << out.spheres_used << " spheres (threshold "
      << o.max_rms_px << " px)";
    out.reason = r.str();
  } else {
    out.status = ViewStatus::ok;
  }
  return out;
}

}  // namespace ctk

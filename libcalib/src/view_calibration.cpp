#include "ctk/calib/view_calibration.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <string>

#include "ctk/calib/pose_fit.hpp"
#include "ctk/calib/sphere_matching.hpp"
#include "ctk/calib/sphere_profile_fit.hpp"
#include "ctk/core/error.hpp"
#include "ctk/core/statistics.hpp"

namespace ctk {

namespace {

// Whether the ray from the source to a sphere on the wall grazes it. The wall is a cylinder, so
// what matters is the ray across the axis: at the sphere's radius r the 2D line passes the axis at
// r |sin| of its angle to the radial direction, and |cos| below 0.3 puts it within 5 % of r, on
// the silhouette. Taken in 3D instead, every ray of a view along the axis would look grazing.
bool grazes_wall(const Eigen::Vector3d& sphere, const Eigen::Vector3d& source) {
  constexpr double kGrazingCosine = 0.3;
  const Eigen::Vector2d radial = sphere.head<2>(), across = (sphere - source).head<2>();
  if (radial.norm() == 0 || across.norm() < 1e-9 * (sphere - source).norm()) return false;  // down the bore
  return std::abs(radial.normalized().dot(across.normalized())) < kGrazingCosine;
}

// Looking within a few degrees of the holder's axis, the spheres sit on the steep edge of the
// wall's end-on shadow (rays running tens of mm inside the tube), where even the search over the
// running median may find too few: the reason then says how close to the axis the first guess looks.
std::string along_the_axis_note(const Rigid& T_camera_holder) {
  constexpr double kNearAxisDeg = 10;
  const double angle = std::acos(std::min(1.0, std::abs(T_camera_holder.linear().col(2).z()))) * 180 / M_PI;
  if (angle >= kNearAxisDeg) return {};
  std::ostringstream note;
  note.precision(2);
  note << std::fixed << "; the first guess looks " << angle
       << " deg from the holder axis, where the tube, seen end on, puts the spheres on the steep edge of its shadow";
  return note.str();
}

// Whether a wall declared without its ends has an unknown shadow in this view: a ray at angle
// theta to the axis crosses the wall's thickness t over t / tan(theta) along it, so below
// tan(theta) = 2 t / L (L the spheres' extent along the axis) even a ray through the middle of the
// spheres' band runs inside the wall beyond the band, where the tube's unknown ends decide its
// path (4.3 deg for the reference holder).
bool ends_decide_shadow(const Holder& holder, const Rigid& T_camera_holder) {
  if (!holder.wall || holder.wall->ends_mm || holder.spheres_mm.empty()) return false;
  const double band = holder.tau_max() - holder.tau_min();
  const double thickness = holder.wall->outer_radius_mm - holder.wall->inner_radius_mm;
  const double cosine = std::min(1.0, std::abs(T_camera_holder.linear().col(2).z()));
  const double tangent = std::sqrt(1 - cosine * cosine) / std::max(cosine, 1e-12);
  return tangent * band < 2 * thickness;
}

struct Prediction {
  std::vector<Eigen::Vector2d> uv;
  std::vector<bool> visible;  // on the detector with room for the background ring (and, without a
                              // declared wall, not on its silhouette)
  std::vector<bool> usable;   // visible and apart from every other sphere
};

// Two spheres closer than this share pixels of their centroid windows.
double touching_distance_px(double radius_px) { return 2 * radius_px + 4; }

Prediction predict(const Eigen::Matrix3d& K, const Rigid& T, const Holder& holder, const Detector& detector, double radius_px) {
  Prediction p;
  // The source in the holder frame: rays to spheres on the holder's silhouette graze the wall,
  // whose steep edge there defeats a planar background; unless the wall is declared (then the
  // profile fit models its shadow), those spheres are left out.
  const Eigen::Vector3d source = T.inverse().translation();
  for (const auto& X : holder.spheres_mm) {
    const Eigen::Vector3d c = K * (T * X);
    p.uv.push_back(c.head<2>() / c.z());
    const bool grazing = !holder.wall && grazes_wall(X, source);
    p.visible.push_back(c.z() > 0 && detector.contains(p.uv.back(), radius_px + 6) && !grazing);
  }
  const double apart = touching_distance_px(radius_px);
  p.usable = p.visible;
  for (std::size_t i = 0; i < p.uv.size(); ++i)
    for (std::size_t j = i + 1; j < p.uv.size(); ++j)
      if ((p.uv[i] - p.uv[j]).norm() < apart) p.usable[i] = p.usable[j] = false;
  return p;
}

// Spheres the detector missed or the match left out (mostly pairs whose projections touch, and
// spheres on the wall's silhouette, where the image is a ridge rather than a bump) are looked for
// where the fitted pose predicts them. Touching ones are fitted together; a ball is kept when it
// is as strong as the matched ones (within 30 % of their median). Balls closer than a radius
// cannot be told apart and are left out.
void recover_missed_spheres(const Image& image, const Prediction& p, double radius_px, std::vector<double> strengths,
                            const ProfileFitOptions& fit_options, const BackgroundShape& wall_shadow,
                            const std::optional<RadialDistortion>& distortion, std::vector<SphereMatch>& matches,
                            const std::vector<SphereMatch>& dropped, std::vector<SphereDetection>& measured,
                            std::vector<SphereDetection>& detections) {
  if (strengths.empty()) return;
  const double typical = median_in_place(strengths);
  const std::size_t n = p.uv.size();
  std::vector<bool> taken(n, false), candidate(n);
  for (const auto& m : matches) taken[static_cast<std::size_t>(m.sphere)] = true;
  for (const auto& m : dropped) taken[static_cast<std::size_t>(m.sphere)] = true;
  for (std::size_t k = 0; k < n; ++k) candidate[k] = p.visible[k] && !taken[k];
  const double apart = touching_distance_px(radius_px);
  for (std::size_t i = 0; i < n; ++i)
    for (std::size_t j = i + 1; j < n; ++j) {
      const double d = (p.uv[i] - p.uv[j]).norm();
      if (d < radius_px || (d < apart && (taken[i] || taken[j]))) candidate[i] = candidate[j] = false;
    }
  // Clusters: candidates linked by touching neighbours (a flood fill over the pairs).
  std::vector<int> cluster(n, -1);
  int clusters = 0;
  for (std::size_t seed = 0; seed < n; ++seed) {
    if (!candidate[seed] || cluster[seed] >= 0) continue;
    std::vector<std::size_t> stack{seed};
    cluster[seed] = clusters;
    while (!stack.empty()) {
      const std::size_t i = stack.back();
      stack.pop_back();
      for (std::size_t j = 0; j < n; ++j)
        if (candidate[j] && cluster[j] < 0 && (p.uv[i] - p.uv[j]).norm() < apart) {
          cluster[j] = clusters;
          stack.push_back(j);
        }
    }
    ++clusters;
  }
  for (int c = 0; c < clusters; ++c) {
    std::vector<std::size_t> members;
    std::vector<SphereDetection> found;
    for (std::size_t k = 0; k < n; ++k)
      if (cluster[k] == c) {
        members.push_back(k);
        SphereDetection d;
        d.uv = distortion ? distortion->measured_from_ideal(p.uv[k]) : p.uv[k];
        found.push_back(d);
      }
    const std::vector<bool> refined = refine_cluster_by_profile_fit(image, radius_px, found, fit_options, wall_shadow);
    for (std::size_t m = 0; m < members.size(); ++m) {
      if (!refined[m] || std::abs(found[m].strength - typical) > 0.3 * typical) continue;
      measured.push_back(found[m]);
      if (distortion) found[m].uv = distortion->ideal_from_measured(found[m].uv);
      detections.push_back(found[m]);
      matches.push_back(
          {static_cast<int>(members[m]), static_cast<int>(detections.size() - 1), (found[m].uv - p.uv[members[m]]).norm()});
    }
  }
}

// What calibrate_view works on: one view's image, the first guess and the scan's constants.
struct ViewProblem {
  const Image& image;
  const Eigen::Matrix3d& K;
  const Rigid& initial;
  const Holder& holder;
  const Detector& detector;
  const CalibrationOptions& options;
  const std::optional<RadialDistortion>& distortion;
  double radius_px;
};

// A match of detections to spheres and the pose fitted to it.
struct Attempt {
  std::vector<SphereMatch> matches;
  std::vector<SphereMatch> dropped;  // matched, but left out as outliers
  PoseFit fit;
};

// One view's calibration in its steps: spheres detected near the first guess, the search over
// shifts of the predicted pattern (match, fit, match again, drop outliers), the matched centres
// refined by profile fits and the missed spheres recovered, then refits under a declared wall's
// shadow seen from the fitted pose.
class ViewCalibrator {
 public:
  explicit ViewCalibrator(const ViewProblem& problem)
      : v_(problem), first_(predict(v_.K, v_.initial, v_.holder, v_.detector, v_.radius_px)) {
    detection_.radius_px = v_.radius_px;
    detection_.region = search_region();
    detect();
  }

  int detection_count() const { return static_cast<int>(detections_.size()); }

  // Whether an attempt is good enough to end the search: half the spheres that stand apart (at
  // least the minimum) within the residual limit.
  bool holds(const Attempt& a) const {
    return static_cast<int>(a.matches.size()) >= std::max(v_.options.min_spheres, usable_count() / 2) &&
           a.fit.rms_px <= v_.options.max_rms_px;
  }

  // The first guess's pattern as it is, then (unless that holds) shifted onto the detections.
  Attempt search() const {
    Attempt found = attempt(Eigen::Vector2d::Zero());
    if (holds(found)) return found;
    for (const auto& shift : candidate_shifts(first_.uv, first_.usable, detections_, v_.options.search_px, 8)) {
      if (shift.norm() == 0) continue;
      Attempt a = attempt(shift);
      if (better(a, found)) found = std::move(a);
    }
    return found;
  }

  // Where the background is far from planar, as when the tube is seen end on and the spheres sit
  // on the steep edge of its ring-shaped shadow, the detector misses most spheres (0 to 10 of the
  // 12 to 18 apart, within 5 deg of the axis, reference holder): they are looked for again in the
  // image less its running median, whose coarse first round also matches touching spheres. The
  // better search stands, with its detections.
  Attempt search_again_on_an_edge_preserving_background(Attempt best) {
    detection_.edge_preserving_background = true;
    coarse_with_touching_ = true;
    std::vector<SphereDetection> plain_measured = std::move(measured_), plain_detections = std::move(detections_);
    detect();
    Attempt again = search();
    if (better(again, best)) return again;
    measured_ = std::move(plain_measured);
    detections_ = std::move(plain_detections);
    return best;
  }

  std::string why_no_pattern_matched() const {
    const int usable = usable_count();
    const auto on_detector = std::count(first_.visible.begin(), first_.visible.end(), true);
    const int min_spheres = v_.options.min_spheres;
    if (usable < min_spheres && on_detector >= min_spheres)
      return "the image cannot fix the pose: the first guess puts " + std::to_string(on_detector) +
             " spheres on the detector, but only " + std::to_string(usable) +
             " stand apart from the others (the projected helix overlaps itself, as when looking along the holder axis)";
    return "too few spheres: no consistent match of the " + std::to_string(detection_count()) +
           " detections near the first-guess pose (at least " + std::to_string(min_spheres) + " spheres needed)" +
           along_the_axis_note(v_.initial);
  }

  // The matched spheres' centres from their whole profiles, then the spheres missed so far, then
  // the final fit and outlier drop. A sphere whose profile fit fails keeps its centroid. A declared
  // wall's shadow, seen from the pose fitted so far, is part of the background.
  void refine_centres_by_profile_fits(Attempt& best) {
    shadow_pose_ = best.fit.T_camera_holder;
    const BackgroundShape wall_shadow = shadow_seen_from(shadow_pose_);
    std::vector<double> strengths;
    for (const auto* list : {&best.matches, &best.dropped})
      for (const auto& m : *list) {
        const auto i = static_cast<std::size_t>(m.detection);
        refine_by_profile_fit(v_.image, v_.radius_px, measured_[i], profile_fit_options(), wall_shadow);
        undistort(i);
        strengths.push_back(measured_[i].strength);
      }
    recover_missed_spheres(v_.image, predict(v_.K, best.fit.T_camera_holder, v_.holder, v_.detector, v_.radius_px), v_.radius_px,
                           strengths, profile_fit_options(), wall_shadow, v_.distortion, best.matches, best.dropped, measured_,
                           detections_);
    best.fit = fit_matches(best.fit.T_camera_holder, best.matches);
    drop_outliers(best);
  }

  // The shadow came from the pose of the centroids, which the steep edges of the tube's end-on
  // shadow pull by up to a pixel (seed 1 of benchmarks/near_axis_calibration.py, 4.8 deg from the
  // axis: 0.52 px RMS, 0.05 px with the shadow seen from the fitted pose). A sphere whose window
  // holds a bend of the shadow (shadow_bends) and which the fitted pose moved by more than a tenth
  // of a pixel is fitted again under the shadow seen from the new pose, and the pose refitted,
  // outliers judged afresh; at most three rounds. Only a wall with its ends: an infinitely long
  // tube's shadow is wrong where rays reach the ends, and refitting under it moves the spheres
  // further from the truth (0.55-0.9 px RMS, 1.9-4.9 deg).
  void refit_under_the_shadow_of_the_fitted_pose(Attempt& best) {
    constexpr double kSettledPx = 0.1;
    for (int round = 0; round < 3 && v_.holder.wall && v_.holder.wall->ends_mm; ++round) {
      const Rigid pose = best.fit.T_camera_holder;
      const BackgroundShape shadow = shadow_seen_from(pose);
      std::vector<SphereMatch> moved;
      for (const auto* list : {&best.matches, &best.dropped})
        for (const auto& m : *list) {
          const Eigen::Vector3d& X = v_.holder.spheres_mm[static_cast<std::size_t>(m.sphere)];
          const Eigen::Vector2d now = projected(pose, X);
          if ((now - projected(shadow_pose_, X)).norm() > kSettledPx &&
              shadow_bends(shadow, v_.distortion ? v_.distortion->measured_from_ideal(now) : now))
            moved.push_back(m);
        }
      if (moved.empty()) break;
      // A round that fits worse says the declared shadow is not the image's (ends declared wrong):
      // the previous round stands.
      Attempt before = best;
      const std::vector<SphereDetection> measured_before = measured_, detections_before = detections_;
      shadow_pose_ = pose;
      for (const auto& m : moved) {
        const auto i = static_cast<std::size_t>(m.detection);
        refine_by_profile_fit(v_.image, v_.radius_px, measured_[i], profile_fit_options(), shadow);
        undistort(i);
      }
      best.matches.insert(best.matches.end(), best.dropped.begin(), best.dropped.end());
      best.dropped.clear();
      best.fit = fit_matches(best.fit.T_camera_holder, best.matches);
      drop_outliers(best);
      if (best.fit.rms_px > before.fit.rms_px) {
        best = std::move(before);
        measured_ = measured_before;
        detections_ = detections_before;
        break;
      }
    }
  }

  // The calibration the attempt gives: its pose and matrix, the pairs used and left out, and the
  // status its residual earns (or why it has none).
  ViewCalibration result(const Attempt& best, ViewCalibration out) const {
    const std::vector<SphereMatch>& matches = best.matches;
    const PoseFit& fit = best.fit;
    out.spheres_used = static_cast<int>(matches.size());
    if (out.spheres_used < v_.options.min_spheres) {
      out.reason = "too few spheres: " + std::to_string(out.spheres_used) + " matched of " + std::to_string(out.detections) +
                   " detected (at least " + std::to_string(v_.options.min_spheres) + " needed)";
      return out;
    }
    out.rms_px = fit.rms_px;
    out.T_camera_holder = fit.T_camera_holder;
    out.P = ProjectionMatrix::compose(v_.K, fit.T_camera_holder);
    for (int a = 0; a < 3; ++a) out.translation_sigma_mm[a] = fit.translation_sigma_mm[a];
    out.rotation_sigma_deg = fit.rotation_sigma_deg;
    for (const auto& m : matches) {
      out.spheres.push_back(m.sphere);
      out.detected_px.push_back(detections_[static_cast<std::size_t>(m.detection)].uv);
      out.fitted_px.push_back(out.P->project(v_.holder.spheres_mm[static_cast<std::size_t>(m.sphere)]));
    }
    for (const auto& m : best.dropped) {
      out.outlier_spheres.push_back(m.sphere);
      out.outlier_detected_px.push_back(detections_[static_cast<std::size_t>(m.detection)].uv);
    }
    if (!fit.converged) {
      out.reason = "pose fit did not converge";
    } else {
      out.residual_decides = true;
      judge_residual(out, v_.options.max_rms_px);
    }
    return out;
  }

 private:
  ProfileFitOptions profile_fit_options() const {
    ProfileFitOptions o;
    o.contrast_loss = v_.options.contrast_loss;
    return o;
  }

  // Spheres are looked for only where the first guess can have put them: a shift of the pattern
  // beyond the search is never matched. Most of a detector sees no sphere, and the filters over the
  // whole image were a fifth of a view's time (perf on ctk calibrate, 120 views of 720 x 720).
  Eigen::AlignedBox2d search_region() const {
    Eigen::AlignedBox2d region;
    for (const auto& X : v_.holder.spheres_mm)
      if (const Eigen::Vector3d c = v_.K * (v_.initial * X); c.z() > 0) {
        const Eigen::Vector2d ideal = c.head<2>() / c.z();  // the image holds the spheres where the distortion puts them
        region.extend(v_.distortion ? v_.distortion->measured_from_ideal(ideal) : ideal);
      }
    if (region.isEmpty()) return region;
    const double margin = v_.options.search_px + 2 * v_.radius_px + 8;
    region.min().array() -= margin;
    region.max().array() += margin;
    const Eigen::AlignedBox2d image(Eigen::Vector2d(0, 0), Eigen::Vector2d(v_.image.cols - 1, v_.image.rows - 1));
    return region.intersects(image) ? region : Eigen::AlignedBox2d(Eigen::Vector2d(0, 0), Eigen::Vector2d(0, 0));
  }

  // `measured_` are where the centres are in the image (profile fits refine them there);
  // `detections_` are the same centres where an ideal pinhole detector would have them (a declared
  // distortion removed), which is what matching and the pose fit compare with projections.
  void detect() {
    measured_ = detect_spheres(v_.image, detection_);
    detections_ = measured_;
    for (std::size_t i = 0; i < detections_.size(); ++i) undistort(i);
  }

  void undistort(std::size_t i) {
    detections_[i].uv = v_.distortion ? v_.distortion->ideal_from_measured(measured_[i].uv) : measured_[i].uv;
  }

  int usable_count() const { return static_cast<int>(std::count(first_.usable.begin(), first_.usable.end(), true)); }

  PoseFit fit_matches(const Rigid& start, const std::vector<SphereMatch>& matches) const {
    std::vector<Eigen::Vector3d> X;
    std::vector<Eigen::Vector2d> uv;
    for (const auto& m : matches) {
      X.push_back(v_.holder.spheres_mm[static_cast<std::size_t>(m.sphere)]);
      uv.push_back(detections_[static_cast<std::size_t>(m.detection)].uv);
    }
    return fit_pose(v_.K, start, X, uv, v_.options.robust_px);
  }

  // Spheres whose centre a nearby edge of the sample has pulled (background not planar) leave
  // residuals far beyond the rest: those beyond 3 robust deviations (at least 0.25 px) are dropped
  // and the pose refitted once.
  void drop_outliers(Attempt& a) const {
    const double limit = std::max(0.25, 3 * 1.4826 * median(a.fit.residual_px));
    std::vector<SphereMatch> kept, dropped;
    for (std::size_t i = 0; i < a.matches.size(); ++i) (a.fit.residual_px[i] <= limit ? kept : dropped).push_back(a.matches[i]);
    if (!dropped.empty() && static_cast<int>(kept.size()) >= v_.options.min_spheres) {
      a.matches = std::move(kept);
      a.dropped.insert(a.dropped.end(), dropped.begin(), dropped.end());
      a.fit = fit_matches(a.fit.T_camera_holder, a.matches);
    }
  }

  // One shift of the predicted pattern: match, fit, then match again from the fitted pose with a
  // tight gate and refit, then drop outliers and refit once. Empty when too few match.
  Attempt attempt(const Eigen::Vector2d& shift) const {
    Attempt a;
    Rigid pose = v_.initial;
    Eigen::Vector2d s = shift;
    double gate = 4.0;
    for (int round = 0; round < 3; ++round) {
      const Prediction p = round == 0 ? first_ : predict(v_.K, pose, v_.holder, v_.detector, v_.radius_px);
      a.matches = match_spheres(p.uv, round == 0 && coarse_with_touching_ ? p.visible : p.usable, detections_, s, gate);
      if (static_cast<int>(a.matches.size()) < v_.options.min_spheres) return Attempt{};
      a.fit = fit_matches(pose, a.matches);
      pose = a.fit.T_camera_holder;
      s = Eigen::Vector2d::Zero();
      gate = 1.5;
    }
    // A uniform helix maps onto itself under a screw by one sphere (14.4 deg about its axis with a
    // slide along it): such a solution matches almost every sphere. The first guess tells them
    // apart, so a pose turned further from it than the guess can be wrong is refused.
    if (rotation_angle_deg(a.fit.T_camera_holder.linear() * v_.initial.linear().transpose()) >
        v_.options.max_first_guess_error_deg)
      return Attempt{};
    drop_outliers(a);
    return a;
  }

  // Among attempts, the one matching most spheres; near-ties (within 10 %) go to the lower RMS.
  static bool better(const Attempt& a, const Attempt& than) {
    if (a.matches.empty()) return false;
    const double more = static_cast<double>(a.matches.size()), have = static_cast<double>(than.matches.size());
    return more > 1.1 * have || (more >= 0.9 * have && a.fit.rms_px < than.fit.rms_px);
  }

  BackgroundShape shadow_seen_from(const Rigid& T_camera_holder) const {
    if (!v_.holder.wall) return nullptr;
    const Rigid holder_from_camera = T_camera_holder.inverse();
    return [this, holder_from_camera](const Eigen::Vector2d& measured_uv) {
      const Eigen::Vector2d uv = v_.distortion ? v_.distortion->ideal_from_measured(measured_uv) : measured_uv;
      const Eigen::Vector3d ray = holder_from_camera.linear() * (K_inverse_ * uv.homogeneous());
      return v_.holder.wall->chord_mm(holder_from_camera.translation(), ray);
    };
  }

  // Whether a sphere's window holds a bend of the shadow: its second difference across the window
  // beyond 0.2 % of it, the pixel averaging's tolerance (a plane or a slope the fit's own plane
  // takes up).
  bool shadow_bends(const BackgroundShape& shadow, const Eigen::Vector2d& centre) const {
    const double reach = v_.radius_px + ProfileFitOptions{}.margin_px;
    const double middle = shadow(centre);
    double largest = std::abs(middle), bend = 0;
    for (const Eigen::Vector2d& step : {Eigen::Vector2d(reach, 0), Eigen::Vector2d(0, reach)}) {
      const double before = shadow(centre - step), after = shadow(centre + step);
      largest = std::max({largest, std::abs(before), std::abs(after)});
      bend = std::max(bend, std::abs(before + after - 2 * middle));
    }
    return bend > 2e-3 * largest;
  }

  Eigen::Vector2d projected(const Rigid& T, const Eigen::Vector3d& X) const {
    const Eigen::Vector3d c = v_.K * (T * X);
    return c.head<2>() / c.z();
  }

  ViewProblem v_;
  Eigen::Matrix3d K_inverse_ = v_.K.inverse();
  Prediction first_;  // the pattern the first guess predicts
  DetectionOptions detection_;
  std::vector<SphereDetection> measured_, detections_;
  bool coarse_with_touching_ = false;  // looking along the axis, few spheres stand apart
  Rigid shadow_pose_;                  // the pose the wall's shadow was last seen from
};

}  // namespace

void CalibrationOptions::validate() const {
  require_option(min_spheres >= 6, "CalibrationOptions.min_spheres", "at least 6 (a pose has 6 parameters)", min_spheres);
  require_option(max_rms_px > 0, "CalibrationOptions.max_rms_px", "a number above 0", max_rms_px);
  require_option(search_px > 0, "CalibrationOptions.search_px", "a number above 0", search_px);
  require_option(robust_px > 0, "CalibrationOptions.robust_px", "a number above 0", robust_px);
  require_option(max_first_guess_error_deg > 0 && max_first_guess_error_deg <= 180,
                 "CalibrationOptions.max_first_guess_error_deg", "a number in (0, 180]", max_first_guess_error_deg);
  require_option(std::abs(contrast_loss) <= kMostContrastLoss, "CalibrationOptions.contrast_loss",
                 "a rate in [-2, 2] per unit line integral", contrast_loss);
}

ViewCalibration calibrate_view(const Image& image, const Eigen::Matrix3d& K, const Rigid& initial, const Holder& holder,
                               const Detector& detector, const CalibrationOptions& o,
                               const std::optional<RadialDistortion>& distortion) {
  o.validate();
  if (ends_decide_shadow(holder, initial)) {  // calibrated as if the wall were not declared
    Holder without_wall = holder;
    without_wall.wall.reset();
    return calibrate_view(image, K, initial, without_wall, detector, o, distortion);
  }
  ViewCalibration out;
  // Projected sphere radius at the holder's depth.
  const double depth = (K.row(2) * initial.translation())(0);
  if (!(depth > holder.sphere_diameter_mm)) {
    std::ostringstream r;
    r << "no pose: the first guess puts the holder's centre " << depth
      << " mm from the source along the beam (behind it or at it)";
    out.reason = r.str();
    return out;
  }
  out.radius_px = 0.5 * holder.sphere_diameter_mm * K(0, 0) / depth;
  ViewCalibrator view({image, K, initial, holder, detector, o, distortion, out.radius_px});
  Attempt best = view.search();
  if (!view.holds(best)) best = view.search_again_on_an_edge_preserving_background(std::move(best));
  out.detections = view.detection_count();
  if (best.matches.empty()) {
    out.reason = view.why_no_pattern_matched();
    return out;
  }
  view.refine_centres_by_profile_fits(best);
  view.refit_under_the_shadow_of_the_fitted_pose(best);
  return view.result(best, std::move(out));
}

void judge_residual(ViewCalibration& view, double limit_px) {
  if (view.rms_px <= limit_px) {
    view.status = ViewStatus::ok;
    view.reason.clear();
    return;
  }
  std::ostringstream r;
  r << "residual above threshold: " << view.rms_px << " px RMS over " << view.spheres_used << " spheres (threshold " << limit_px
    << " px)";
  view.status = ViewStatus::rejected;
  view.reason = r.str();
}

double residual_limit_px(const std::vector<ViewCalibration>& views, const CalibrationOptions& options) {
  std::vector<double> rms;
  for (const ViewCalibration& v : views)
    if (v.residual_decides) rms.push_back(v.rms_px);
  if (rms.empty()) return options.max_rms_px;
  return std::max(options.max_rms_px, 2 * median(rms));
}

}  // namespace ctk

#include "ctk/calib/calibration_pictures.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <opencv2/imgproc.hpp>
#include <optional>

#include "ctk/core/chart.hpp"
#include "ctk/geom/nominal_geometry.hpp"
#include "ctk/geom/sphere_map.hpp"
#include "ctk/measure/projection_reading.hpp"

namespace ctk {

void write_residual_per_view_png(const std::vector<ViewCalibration>& views, double threshold_px,
                                 const std::filesystem::path& png) {
  double top = 1.25 * threshold_px;
  for (const auto& v : views) top = std::max(top, 1.05 * v.rms_px);
  const double n = static_cast<double>(std::max<std::size_t>(views.size(), 1));
  Chart chart(760, 300, {-0.5, n - 0.5, 0, top, "reprojection RMS per view", "view", "RMS (px)"});
  chart.ticks(std::max(1.0, nice_step(n, 10)), nice_step(top, 5));
  chart.line(-0.5, threshold_px, n - 0.5, threshold_px, colour::orange);
  for (std::size_t i = 0; i < views.size(); ++i) {
    const auto& v = views[i];
    const double x = static_cast<double>(i);
    if (v.status == ViewStatus::ok)
      chart.dot(x, v.rms_px, colour::ramp(v.rms_px / threshold_px));
    else if (v.status == ViewStatus::rejected)
      chart.cross(x, v.P ? v.rms_px : 0.97 * top, colour::red);
    else
      chart.cross(x, 0.97 * top, colour::grey);
  }
  chart.legend({{"calibrated (colour: RMS / threshold)", colour::green, Mark::dot},
                {"rejected", colour::red, Mark::cross},
                {"skipped", colour::grey, Mark::cross},
                {"threshold", colour::orange, Mark::line}});
  chart.save(png);
}

void write_detections_png(const Image& im, const ViewCalibration& view, const std::filesystem::path& png, double magnify) {
  // Grey levels from the 1st to the 99.9th percentile of the line integrals.
  std::vector<float> sorted = im.pixels;
  std::sort(sorted.begin(), sorted.end());
  const double low = sorted[sorted.size() / 100], high = sorted[std::min(sorted.size() - 1, sorted.size() * 999 / 1000)];
  cv::Mat grey(im.rows, im.cols, CV_8U);
  for (int r = 0; r < im.rows; ++r)
    for (int c = 0; c < im.cols; ++c) {
      const double f =
          (im.pixels[static_cast<std::size_t>(r) * static_cast<std::size_t>(im.cols) + static_cast<std::size_t>(c)] - low) /
          std::max(high - low, 1e-12);
      grey.at<unsigned char>(r, c) = static_cast<unsigned char>(std::clamp(255.0 * (1.0 - f), 0.0, 255.0));
    }
  Canvas picture(im.cols, im.rows);
  picture.paste(grey, 0, 0);
  // Pixel centres at integer (u, v) are at canvas coordinates + 0.5.
  const auto pt = [](const Eigen::Vector2d& p) { return cv::Point2d(p.x() + 0.5, p.y() + 0.5); };
  for (std::size_t k = 0; k < view.detected_px.size(); ++k) {
    const Eigen::Vector2d& d = view.detected_px[k];
    const Eigen::Vector2d& f = view.fitted_px[k];
    picture.circle(pt(f), view.radius_px + 3, colour::green, false);
    picture.line(pt(f), pt(f + magnify * (d - f)), colour::red, 1.5);
    picture.text(std::to_string(view.spheres[k]), pt(f) + cv::Point2d(7, -7), 10, colour::blue);
  }
  char caption[160];
  std::snprintf(caption, sizeof caption, "%s, %d spheres, RMS %.3f px; green: fitted, red: residual x%g", to_string(view.status),
                view.spheres_used, view.rms_px, magnify);
  // As large as 12 px allows within the picture's width.
  const double size = std::min(12.0, 12.0 * (im.cols - 16) / std::max(picture.text_width(caption, 12), 1.0));
  picture.rectangle({0, 0, picture.text_width(caption, size) + 16, 26}, colour::white, true);
  picture.text(caption, {8, 18}, size, colour::red);
  picture.save(png);
}

Eigen::Vector3d source_direction_in_holder(const Rigid& T_camera_holder) {
  return T_camera_holder.inverse().translation().normalized();
}

void write_view_directions_png(const std::vector<ViewDirection>& views, double threshold_px, const std::filesystem::path& png) {
  // Lambert cylindrical equal-area: x = longitude (shown in degrees), y = sin(latitude).
  constexpr double kDeg = 180 / M_PI;
  Chart chart(900, 287,
              {-180, 180, -1, 1, "view directions (source seen from the holder), equal-area; colour: RMS / threshold",
               "longitude about the holder axis (deg)", "sin(latitude)"});
  for (int lon = -180; lon <= 180; lon += 30) chart.line(lon, -1, lon, 1, colour::light);
  for (int lat = -60; lat <= 60; lat += 30) {
    const double y = std::sin(lat / kDeg);
    chart.line(-180, y, 180, y, colour::light);
  }
  chart.ticks(60, 0.5);
  for (const auto& v : views) {
    const MapPoint p = equal_area_map(v.source_in_holder);
    if (v.status == ViewStatus::ok)
      chart.dot(p.x * kDeg, p.y, colour::ramp(v.rms_px / threshold_px), 3);
    else
      chart.cross(p.x * kDeg, p.y, v.status == ViewStatus::rejected ? colour::red : colour::grey);
  }
  chart.legend(
      {{"calibrated", colour::green, Mark::dot}, {"rejected", colour::red, Mark::cross}, {"skipped", colour::grey, Mark::cross}});
  chart.save(png);
}

std::vector<std::string> write_calibration_pictures(const ScanDescription& scan, const ScanCalibration& c, double threshold_px,
                                                    const std::filesystem::path& stem) {
  const auto named = [&](const std::string& what) { return std::filesystem::path(stem.string() + "." + what + ".png"); };
  std::vector<std::string> written;
  write_residual_per_view_png(c.views, threshold_px, named("residuals"));
  written.push_back(named("residuals").filename().string());

  const std::vector<NominalView> nominal = nominal_views(scan);
  std::vector<ViewDirection> directions;
  for (std::size_t v = 0; v < c.views.size(); ++v) {
    const ViewCalibration& r = c.views[v];
    std::optional<Rigid> T = r.T_camera_holder ? r.T_camera_holder : nominal[v].T_camera_holder;
    if (!T && nominal[v].P) T = nominal[v].P->decompose().T_camera_frame;
    if (T) directions.push_back({source_direction_in_holder(*T), r.status, r.rms_px});
  }
  write_view_directions_png(directions, threshold_px, named("directions"));
  written.push_back(named("directions").filename().string());

  std::vector<std::size_t> ok, shown;
  for (std::size_t v = 0; v < c.views.size(); ++v)
    if (c.views[v].status == ViewStatus::ok) ok.push_back(v);
  std::sort(ok.begin(), ok.end(), [&](std::size_t a, std::size_t b) { return c.views[a].rms_px < c.views[b].rms_px; });
  if (!ok.empty()) shown = {ok[ok.size() / 2], ok.back()};
  for (std::size_t v = 0; v < c.views.size(); ++v)
    if (c.views[v].status == ViewStatus::rejected && c.views[v].radius_px > 0) {
      shown.push_back(v);
      break;
    }
  const std::optional<FlatDark> flat_dark = read_flat_dark(scan);
  for (std::size_t v : shown) {
    char what[32];
    std::snprintf(what, sizeof what, "view-%04zu", v);
    if (std::find(written.begin(), written.end(), named(what).filename().string()) != written.end()) continue;
    write_detections_png(read_line_integrals(scan, static_cast<int>(v), flat_dark), c.views[v], named(what));
    written.push_back(named(what).filename().string());
  }
  return written;
}

}  // namespace ctk

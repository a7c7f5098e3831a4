#include "ctk/plan/plan_pictures.hpp"

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>

#include "ctk/core/chart.hpp"
#include "ctk/core/image_io.hpp"
#include "ctk/geom/sphere_map.hpp"

namespace ctk {

namespace {

constexpr double kDeg = 180 / M_PI;

cv::Mat slice_picture(const Volume& v, int k, float ceiling, int size) {
  const auto& n = v.layout.size;
  cv::Mat grey(n[1], n[0], CV_8UC1);
  for (int j = 0; j < n[1]; ++j)
    for (int i = 0; i < n[0]; ++i)
      grey.at<unsigned char>(n[1] - 1 - j, i) =
          static_cast<unsigned char>(std::clamp(255.0f * v.at(i, j, k) / ceiling, 0.0f, 255.0f));
  cv::Mat big, colour;
  cv::resize(grey, big, cv::Size(size, size * n[1] / n[0]), 0, 0, cv::INTER_NEAREST);
  cv::cvtColor(big, colour, cv::COLOR_GRAY2BGR);
  return colour;
}

// The picture under a label of two lines (every panel of a row gets the same height).
cv::Mat labelled(const cv::Mat& picture, const std::string& line1, const std::string& line2 = "") {
  const int top = 46;
  Canvas out(picture.cols, picture.rows + top);
  out.paste(picture, 0, top);
  out.text(line1, {6, 18}, 13);
  out.text(line2, {6, 38}, 13);
  return out.bgr();
}

// One equal-area map of the candidates coloured by `value` (from its least to its greatest), with
// the requested directions marked.
cv::Mat direction_map(const PlanningResult& r, const std::vector<double>& value, const std::string& title) {
  double least = 0, most = 0;
  if (!value.empty()) {
    const auto [lo, hi] = std::minmax_element(value.begin(), value.end());
    least = *lo;
    most = *hi;
  }
  Chart chart(900, 287, {-180, 180, -1, 1, title, "longitude about the holder axis (deg)", "sin(latitude)"});
  for (std::size_t c = 0; c < r.candidates.size(); ++c) {
    const MapPoint p = equal_area_map(r.candidates[c]);
    const bool refused = c < r.weights.size() && r.weights[c].reach == 0;
    const double level = (most > least && c < value.size()) ? (value[c] - least) / (most - least) : 0.0;
    const cv::Scalar fill = refused ? colour::light : colour::ramp(level);
    chart.dot(p.x * kDeg, p.y, fill, 6);
  }
  chart.ticks(60, 0.5);
  for (const PlannedViewRecord& v : r.views) {
    const MapPoint p = equal_area_map(v.requested);
    if (!v.calibrated)
      chart.cross(p.x * kDeg, p.y, colour::red, 5);
    else
      chart.dot(p.x * kDeg, p.y, v.scout ? colour::black : colour::blue, v.scout ? 2 : 4);
  }
  chart.legend({{"scout view", colour::black, Mark::dot},
                {"planned view", colour::blue, Mark::dot},
                {"refused or not calibrated", colour::red, Mark::cross},
                {"candidate unreachable", colour::light, Mark::dot}});
  return chart.picture();
}

}  // namespace

void write_plan_map_png(const PlanningResult& r, const std::filesystem::path& png) {
  std::vector<double> density;
  for (const CandidateWeight& w : r.weights) density.push_back(w.density);
  cv::Mat picture;
  const cv::Mat damage =
      direction_map(r, r.damage_mm, "directions (equal-area); colour: predicted absorber path, green least, red most");
  const cv::Mat wanted = direction_map(
      r, density, "colour: view density the sample's edges want, green least, red most (from the last coarse volume)");
  cv::vconcat(damage, wanted, picture);
  write_png_atomically(picture, png);
}

void write_trajectory_comparison_png(const std::vector<ComparedTrajectory>& t, const Volume& truth,
                                     const std::filesystem::path& png) {
  if (t.empty() || t.front().quality.profiles.empty()) return;
  const std::array<int, 3> through = t.front().quality.profiles.front().through;
  const float ceiling = 1.5f * preview_ceiling(truth);
  const int size = 300;
  std::vector<cv::Mat> top, bottom;
  top.push_back(labelled(slice_picture(truth, through[2], ceiling, size), "truth (z slice " + std::to_string(through[2]) + ")"));
  double hi = 0;
  for (const auto& c : t)
    for (float v : c.quality.profiles.front().reconstruction) hi = std::max(hi, static_cast<double>(v));
  for (float v : t.front().quality.profiles.front().truth) hi = std::max(hi, static_cast<double>(v));
  const int width = static_cast<int>(t.size() + 1) * size;
  for (const auto& c : t) {
    char line1[160], line2[160];
    // Short enough for the picture's width; the gradients are in comparison.json and the chart.
    // Without the absorbers (and their neighbours) the RMSE shows what their level hides.
    std::snprintf(line1, sizeof line1, "%s: RMSE %.5f/mm", c.name.c_str(), c.quality.rmse_per_mm);
    std::snprintf(line2, sizeof line2, "without absorbers %.5f/mm", c.quality.rmse_outside_absorbers_per_mm);
    top.push_back(labelled(slice_picture(*c.reconstruction, through[2], ceiling, size), line1, line2));
  }
  cv::Mat slices;
  cv::hconcat(top, slices);
  // One chart: every trajectory's x profile and the truth's.
  const LineProfile& first = t.front().quality.profiles.front();
  Chart chart(
      width - 110, 220,
      {0, static_cast<double>(first.truth.size()), 0, 1.05 * hi, "profile along x through the sample's centre", "voxel", "1/mm"});
  const cv::Scalar colours[] = {colour::blue, colour::orange, colour::green, colour::red};
  auto draw = [&](const std::vector<float>& p, const cv::Scalar& c) {
    for (std::size_t s = 1; s < p.size(); ++s) chart.line(s - 1.0, p[s - 1], static_cast<double>(s), p[s], c, 1);
  };
  draw(first.truth, colour::grey);
  std::vector<LegendEntry> key = {{"truth", colour::grey, Mark::line}};
  for (std::size_t i = 0; i < t.size(); ++i) {
    draw(t[i].quality.profiles.front().reconstruction, colours[i % 4]);
    key.push_back({t[i].name, colours[i % 4], Mark::line});
  }
  chart.ticks(nice_step(static_cast<double>(first.truth.size()), 8), nice_step(hi, 4));
  chart.legend(key);
  cv::Mat profile = chart.picture();
  if (profile.cols != slices.cols) {
    cv::Mat padded(profile.rows, slices.cols, CV_8UC3, cv::Scalar(255, 255, 255));
    profile(cv::Rect(0, 0, std::min(profile.cols, slices.cols), profile.rows))
        .copyTo(padded(cv::Rect(0, 0, std::min(profile.cols, slices.cols), profile.rows)));
    profile = padded;
  }
  cv::Mat picture;
  cv::vconcat(slices, profile, picture);
  write_png_atomically(picture, png);
}

}  // namespace ctk

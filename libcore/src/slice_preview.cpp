#include "ctk/core/slice_preview.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "ctk/core/chart.hpp"

namespace ctk {

namespace {

std::string number(double x) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.3g", x);
  return buffer;
}

constexpr double kLabelPx = 12;

}  // namespace

void write_slice_preview(const Volume& v, int axis, int index, float low, float high, const std::string& unit,
                         const std::filesystem::path& file) {
  const auto& s = v.layout.size;
  const int across = axis == 0 ? 1 : 0, down = axis == 2 ? 1 : 2;  // volume axes along the picture's columns and rows
  const int w = s[static_cast<std::size_t>(across)], h = s[static_cast<std::size_t>(down)];
  const bool z_up = axis != 2;
  // Whole pixels per voxel, up to about 400 pixels across (a 64-voxel slice stays legible).
  const int zoom = std::max(1, std::min(400 / std::max(w, 1), 600 / std::max(h, 1)));
  const int left = 34, top = 10, bottom = 66, right = 16;
  const int width = std::max(w * zoom + left + right, 300);
  Canvas canvas(width, top + h * zoom + bottom);
  const float span = std::max(high - low, 1e-30f);
  cv::Mat slice(h, w, CV_8UC1);
  for (int r = 0; r < h; ++r)
    for (int c = 0; c < w; ++c) {
      const int k = z_up ? h - 1 - r : r;  // picture row r shows this index along `down`
      int ijk[3] = {index, index, index};
      ijk[across] = c;
      ijk[down] = k;
      const float g = std::clamp((v.at(ijk[0], ijk[1], ijk[2]) - low) / span, 0.0f, 1.0f);
      slice.at<unsigned char>(r, c) = static_cast<unsigned char>(std::lround(255.0f * g));
    }
  canvas.paste(slice, left, top, zoom);
  const char* names = "xyz";
  const double image_bottom = top + h * zoom;
  // Axis names: the picture's columns run along `across`, its rows along `down` (up for z).
  canvas.text(std::string(1, names[across]) + " \u2192", {left + w * zoom - 2.0, image_bottom + 17}, kLabelPx, colour::black,
              TextAnchor::right);
  canvas.text(std::string(1, names[down]) + (z_up ? " \u2192" : " \u2190"), {22, z_up ? top + 2.0 : image_bottom - 2}, kLabelPx,
              colour::black, z_up ? TextAnchor::right : TextAnchor::left, 90);
  // Scale bar: a round length near a quarter of the slice's width.
  const double voxel = v.layout.voxel_mm[across];
  const double width_mm = w * voxel, bar_mm = nice_step(width_mm / 4, 1);
  const double bar_px = bar_mm / voxel * zoom;
  canvas.line({static_cast<double>(left), image_bottom + 12}, {left + bar_px, image_bottom + 12}, colour::black, 3);
  canvas.text(number(bar_mm) + " mm", {left + bar_px + 6, image_bottom + 16}, kLabelPx);
  // Grey bar from low to high.
  const int bar_width = std::min(200, width - left - right);
  const double bar_top = image_bottom + 28;
  cv::Mat ramp(1, bar_width, CV_8UC1);
  for (int x = 0; x < bar_width; ++x)
    ramp.at<unsigned char>(0, x) = static_cast<unsigned char>(std::lround(255.0 * x / std::max(bar_width - 1, 1)));
  cv::Mat bar;
  cv::repeat(ramp, 9, 1, bar);
  canvas.paste(bar, left, static_cast<int>(bar_top));
  canvas.rectangle({left - 0.5, bar_top - 0.5, static_cast<double>(bar_width + 1), 10}, colour::grey);
  canvas.text(number(low), {static_cast<double>(left), bar_top + 24}, kLabelPx - 1);
  canvas.text(number(high) + (unit.empty() ? "" : " " + unit), {static_cast<double>(left + bar_width), bar_top + 24},
              kLabelPx - 1, colour::black, TextAnchor::right);
  canvas.save(file);
}

}  // namespace ctk

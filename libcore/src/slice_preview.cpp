#include "ctk/core/slice_preview.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <opencv2/imgproc.hpp>

#include "ctk/core/chart.hpp"

namespace ctk {

namespace {

std::string number(double x) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.3g", x);
  return buffer;
}

void label(cv::Mat& canvas, const std::string& text, cv::Point at, double scale = 0.45) {
  cv::putText(canvas, text, at, cv::FONT_HERSHEY_SIMPLEX, scale, colour::black, 1, cv::LINE_AA);
}

}  // namespace

void write_slice_preview(const Volume& v, int axis, int index, float low, float high, const std::string& unit,
                         const std::filesystem::path& file) {
  const auto& s = v.layout.size;
  const int across = axis == 0 ? 1 : 0, down = axis == 2 ? 1 : 2;  // volume axes along the picture's columns and rows
  const int w = s[static_cast<std::size_t>(across)], h = s[static_cast<std::size_t>(down)];
  const bool z_up = axis != 2;
  // Whole pixels per voxel, up to about 400 pixels across (a 64-voxel slice stays legible).
  const int zoom = std::max(1, std::min(400 / std::max(w, 1), 600 / std::max(h, 1)));
  const int left = 34, top = 10, bottom = 64, right = 16;
  const int width = std::max(w * zoom + left + right, 300);
  cv::Mat canvas(top + h * zoom + bottom, width, CV_8UC3, cv::Scalar(255, 255, 255));
  const float span = std::max(high - low, 1e-30f);
  for (int r = 0; r < h; ++r)
    for (int c = 0; c < w; ++c) {
      const int k = z_up ? h - 1 - r : r;  // picture row r shows this index along `down`
      int ijk[3] = {index, index, index};
      ijk[across] = c;
      ijk[down] = k;
      const float g = std::clamp((v.at(ijk[0], ijk[1], ijk[2]) - low) / span, 0.0f, 1.0f);
      const unsigned char grey = static_cast<unsigned char>(std::lround(255.0f * g));
      cv::rectangle(canvas, cv::Rect(left + c * zoom, top + r * zoom, zoom, zoom), cv::Scalar(grey, grey, grey), cv::FILLED);
    }
  const char* names = "xyz";
  const int image_bottom = top + h * zoom;
  // Axis names: the picture's columns run along `across`, its rows along `down` (up for z).
  label(canvas, std::string(1, names[across]) + " ->", cv::Point(left + w * zoom - 34, image_bottom + 16));
  label(canvas, std::string(1, names[down]) + (z_up ? " ^" : " v"), cv::Point(2, z_up ? top + 14 : image_bottom - 4));
  // Scale bar: a round length near a quarter of the slice's width.
  const double voxel = v.layout.voxel_mm[across];
  const double width_mm = w * voxel, bar_mm = nice_step(width_mm / 4, 1);
  const int bar_px = static_cast<int>(std::lround(bar_mm / voxel * zoom));
  cv::line(canvas, cv::Point(left, image_bottom + 12), cv::Point(left + bar_px, image_bottom + 12), colour::black, 3);
  label(canvas, number(bar_mm) + " mm", cv::Point(left + bar_px + 6, image_bottom + 17));
  // Grey bar from low to high.
  const int bar_left = left, bar_width = std::min(200, width - left - right), bar_top = image_bottom + 28;
  for (int x = 0; x < bar_width; ++x) {
    const unsigned char grey = static_cast<unsigned char>(std::lround(255.0 * x / std::max(bar_width - 1, 1)));
    cv::line(canvas, cv::Point(bar_left + x, bar_top), cv::Point(bar_left + x, bar_top + 8), cv::Scalar(grey, grey, grey));
  }
  cv::rectangle(canvas, cv::Rect(bar_left, bar_top, bar_width, 9), colour::grey);
  label(canvas, number(low), cv::Point(bar_left, bar_top + 24), 0.4);
  const std::string hi = number(high) + (unit.empty() ? "" : " " + unit);
  label(canvas, hi, cv::Point(bar_left + bar_width - 7 * static_cast<int>(hi.size()), bar_top + 24), 0.4);
  write_png_atomically(canvas, file);
}

}  // namespace ctk

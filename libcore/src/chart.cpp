#include "ctk/core/chart.hpp"

#include <cmath>
#include <cstdio>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <vector>

#include "ctk/core/atomic_write.hpp"

namespace ctk {

cv::Scalar colour::ramp(double fraction) {
  const double f = std::clamp(fraction, 0.0, 1.0);
  // green (60,170,60) -> yellow (40,200,230) -> red (40,40,220), BGR
  if (f < 0.5) return cv::Scalar(60 - 40 * f, 170 + 60 * f, 60 + 340 * f);
  return cv::Scalar(40, 200 - 320 * (f - 0.5), 230 - 20 * (f - 0.5));
}

double nice_step(double span, int ticks) {
  const double raw = span / std::max(ticks, 1), decade = std::pow(10.0, std::floor(std::log10(raw)));
  for (double m : {1.0, 2.0, 5.0})
    if (m * decade >= raw) return m * decade;
  return 10 * decade;
}

Chart::Chart(int plot_width, int plot_height, ChartAxes axes)
    : axes_(std::move(axes)),
      width_(plot_width),
      height_(plot_height),
      canvas_(plot_height + 46 + 46, plot_width + 70 + 20, CV_8UC3, cv::Scalar(255, 255, 255)) {
  cv::rectangle(canvas_, cv::Rect(left_, top_, width_, height_), colour::black, 1);
  const auto font = cv::FONT_HERSHEY_SIMPLEX;
  cv::putText(canvas_, axes_.title, {left_, 18}, font, 0.55, colour::black, 1, cv::LINE_AA);
  cv::putText(canvas_, axes_.x_label, {left_ + width_ / 2 - 60, top_ + height_ + 40}, font, 0.45, colour::black, 1, cv::LINE_AA);
  // The y label sits above the axis, written horizontally (OpenCV has no rotated text).
  cv::putText(canvas_, axes_.y_label, {4, top_ - 6}, font, 0.4, colour::black, 1, cv::LINE_AA);
}

cv::Point Chart::at(double x, double y) const {
  const double fx = (x - axes_.x0) / (axes_.x1 - axes_.x0), fy = (y - axes_.y0) / (axes_.y1 - axes_.y0);
  return {left_ + static_cast<int>(std::lround(fx * width_)), top_ + height_ - static_cast<int>(std::lround(fy * height_))};
}

void Chart::dot(double x, double y, const cv::Scalar& c, int radius) {
  cv::circle(canvas_, at(x, y), radius, c, cv::FILLED, cv::LINE_AA);
}

void Chart::cross(double x, double y, const cv::Scalar& c, int size) {
  const cv::Point p = at(x, y);
  cv::line(canvas_, p + cv::Point(-size, -size), p + cv::Point(size, size), c, 1, cv::LINE_AA);
  cv::line(canvas_, p + cv::Point(-size, size), p + cv::Point(size, -size), c, 1, cv::LINE_AA);
}

void Chart::line(double x0, double y0, double x1, double y1, const cv::Scalar& c, int thickness) {
  cv::line(canvas_, at(x0, y0), at(x1, y1), c, thickness, cv::LINE_AA);
}

void Chart::text(double x, double y, const std::string& s, const cv::Scalar& c) {
  cv::putText(canvas_, s, at(x, y), cv::FONT_HERSHEY_SIMPLEX, 0.4, c, 1, cv::LINE_AA);
}

void Chart::ticks(double x_step, double y_step) {
  char label[32];
  const auto font = cv::FONT_HERSHEY_SIMPLEX;
  // Either axis may run backwards (detector rows grow downwards).
  const double x_lo = std::min(axes_.x0, axes_.x1), x_hi = std::max(axes_.x0, axes_.x1);
  const double y_lo = std::min(axes_.y0, axes_.y1), y_hi = std::max(axes_.y0, axes_.y1);
  // Ticks counted from whole steps: a tick at zero is 0, not the -0 that ceil(-0.3) * step gives.
  auto tick = [](long k, double step) { return k == 0 ? 0.0 : static_cast<double>(k) * step; };
  for (long k = static_cast<long>(std::ceil(x_lo / x_step - 1e-9)); tick(k, x_step) <= x_hi + 1e-9 * x_step; ++k) {
    const double x = tick(k, x_step);
    const cv::Point p = at(x, axes_.y0);
    cv::line(canvas_, p, p + cv::Point(0, 4), colour::black);
    std::snprintf(label, sizeof label, "%g", x);
    cv::putText(canvas_, label, p + cv::Point(-8, 18), font, 0.4, colour::black, 1, cv::LINE_AA);
  }
  for (long k = static_cast<long>(std::ceil(y_lo / y_step - 1e-9)); tick(k, y_step) <= y_hi + 1e-9 * y_step; ++k) {
    const double y = tick(k, y_step);
    const cv::Point p = at(axes_.x0, y);
    cv::line(canvas_, p, p - cv::Point(4, 0), colour::black);
    std::snprintf(label, sizeof label, "%g", y);
    cv::putText(canvas_, label, p + cv::Point(-60, 5), font, 0.4, colour::black, 1, cv::LINE_AA);
  }
}

void write_png_atomically(const cv::Mat& picture, const std::filesystem::path& png) {
  std::vector<unsigned char> bytes;
  cv::imencode(".png", picture, bytes);
  write_file_atomically(png, [&](std::ostream& out) {
    out.write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
  });
}

void Chart::save(const std::filesystem::path& png) const { write_png_atomically(canvas_, png); }

}  // namespace ctk

#include "ctk/core/chart.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace ctk {

namespace {

constexpr double kTitlePx = 14, kLabelPx = 12, kTickPx = 11;

}  // namespace

double nice_step(double span, int ticks) {
  const double raw = span / std::max(ticks, 1), decade = std::pow(10.0, std::floor(std::log10(raw)));
  for (double m : {1.0, 2.0, 5.0})
    if (m * decade >= raw) return m * decade;
  return 10 * decade;
}

std::string tick_label(double value) {
  char label[32];
  std::snprintf(label, sizeof label, "%g", value == 0 ? 0.0 : value);  // -0 == 0: drawn as 0
  return label;
}

Chart::Chart(int plot_width, int plot_height, ChartAxes axes)
    : axes_(std::move(axes)),
      width_(plot_width),
      height_(plot_height),
      canvas_(left_ + plot_width + right_, top_ + plot_height + bottom_) {
  canvas_.rectangle({left_ + 0.5, top_ + 0.5, static_cast<double>(width_), static_cast<double>(height_)}, colour::black);
  canvas_.text(axes_.title, {static_cast<double>(left_), 21}, kTitlePx);
  canvas_.text(axes_.x_label, {left_ + width_ / 2.0, top_ + height_ + 42.0}, kLabelPx, colour::black, TextAnchor::centre);
  canvas_.text(axes_.y_label, {16, top_ + height_ / 2.0}, kLabelPx, colour::black, TextAnchor::centre, 90);
}

cv::Point2d Chart::at(double x, double y) const {
  const double fx = (x - axes_.x0) / (axes_.x1 - axes_.x0), fy = (y - axes_.y0) / (axes_.y1 - axes_.y0);
  return {left_ + 0.5 + fx * width_, top_ + 0.5 + height_ - fy * height_};
}

void Chart::dot(double x, double y, const cv::Scalar& c, double radius) { canvas_.circle(at(x, y), radius, c); }

void Chart::cross(double x, double y, const cv::Scalar& c, double size) {
  const cv::Point2d p = at(x, y);
  canvas_.line(p + cv::Point2d(-size, -size), p + cv::Point2d(size, size), c, 1.5);
  canvas_.line(p + cv::Point2d(-size, size), p + cv::Point2d(size, -size), c, 1.5);
}

void Chart::line(double x0, double y0, double x1, double y1, const cv::Scalar& c, double thickness) {
  canvas_.clip({left_ + 0.5, top_ + 0.5, static_cast<double>(width_), static_cast<double>(height_)});
  canvas_.line(at(x0, y0), at(x1, y1), c, thickness);
  canvas_.unclip();
}

void Chart::text(double x, double y, const std::string& s, const cv::Scalar& c) { canvas_.text(s, at(x, y), kTickPx, c); }

void Chart::ticks(double x_step, double y_step) {
  // Either axis may run backwards (detector rows grow downwards).
  const double x_lo = std::min(axes_.x0, axes_.x1), x_hi = std::max(axes_.x0, axes_.x1);
  const double y_lo = std::min(axes_.y0, axes_.y1), y_hi = std::max(axes_.y0, axes_.y1);
  // Ticks counted in whole steps from zero, so 0.1 + 0.2 never shows as 0.30000000000000004.
  for (long k = static_cast<long>(std::ceil(x_lo / x_step - 1e-9)); static_cast<double>(k) * x_step <= x_hi + 1e-9 * x_step;
       ++k) {
    const double x = static_cast<double>(k) * x_step;
    const cv::Point2d p = at(x, axes_.y0);
    canvas_.line(p, p + cv::Point2d(0, 5), colour::black);
    canvas_.text(tick_label(x), p + cv::Point2d(0, 18), kTickPx, colour::black, TextAnchor::centre);
  }
  for (long k = static_cast<long>(std::ceil(y_lo / y_step - 1e-9)); static_cast<double>(k) * y_step <= y_hi + 1e-9 * y_step;
       ++k) {
    const double y = static_cast<double>(k) * y_step;
    const cv::Point2d p = at(axes_.x0, y);
    canvas_.line(p, p - cv::Point2d(5, 0), colour::black);
    canvas_.text(tick_label(y), p + cv::Point2d(-8, 4), kTickPx, colour::black, TextAnchor::right);
  }
}

void Chart::legend(const std::vector<LegendEntry>& entries) {
  if (entries.empty()) return;
  double widest = 0;
  for (const LegendEntry& e : entries) widest = std::max(widest, canvas_.text_width(e.label, kTickPx));
  const double line_px = 16, mark_px = 22, pad = 6;
  const double w = pad + mark_px + widest + pad, h = pad + line_px * static_cast<double>(entries.size()) + pad / 2;
  const double x = left_ + width_ - w - 6, y = top_ + 6;
  canvas_.rectangle({x, y, w, h}, colour::white, true);
  canvas_.rectangle({x + 0.5, y + 0.5, w, h}, colour::grey);
  for (std::size_t i = 0; i < entries.size(); ++i) {
    const LegendEntry& e = entries[i];
    const double base = y + pad + line_px * (static_cast<double>(i) + 0.75);
    const cv::Point2d mark(x + pad + mark_px / 2 - 2, base - 4);
    if (e.mark == Mark::dot) {
      canvas_.circle(mark, 3, e.colour);
    } else if (e.mark == Mark::cross) {
      canvas_.line(mark + cv::Point2d(-4, -4), mark + cv::Point2d(4, 4), e.colour, 1.5);
      canvas_.line(mark + cv::Point2d(-4, 4), mark + cv::Point2d(4, -4), e.colour, 1.5);
    } else {
      canvas_.line(mark - cv::Point2d(8, 0), mark + cv::Point2d(8, 0), e.colour, 2);
    }
    canvas_.text(e.label, {x + pad + mark_px, base}, kTickPx, e.colour == colour::light ? colour::grey : colour::black);
  }
}

void Chart::save(const std::filesystem::path& png) const { canvas_.save(png); }

cv::Mat Chart::picture() const { return canvas_.bgr(); }

}  // namespace ctk

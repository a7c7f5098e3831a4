#pragma once
// A small plotting canvas for report pictures (OpenCV drawing): data coordinates mapped onto a
// framed plot area, axis labels, and a PNG written atomically. Used by the calibration and
// diagnosis reports, and by the view planner's pictures.
#include <filesystem>
#include <opencv2/core.hpp>
#include <string>

namespace ctk {

struct ChartAxes {
  double x0 = 0, x1 = 1, y0 = 0, y1 = 1;  // data range shown, y0 at the bottom
  std::string title, x_label, y_label;
};

namespace colour {
const cv::Scalar black(0, 0, 0), grey(160, 160, 160), light(225, 225, 225), red(40, 40, 220), green(60, 170, 60),
    blue(200, 110, 30), orange(30, 140, 240);
/// From green (0) through yellow to red (1), for values relative to a threshold.
cv::Scalar ramp(double fraction);
}  // namespace colour

/// Encodes a BGR picture as PNG and writes it whole or not at all.
void write_png_atomically(const cv::Mat& picture, const std::filesystem::path& png);

/// A round tick step (1, 2 or 5 times a power of ten) giving about `ticks` ticks over `span`.
double nice_step(double span, int ticks);

class Chart {
 public:
  Chart(int plot_width, int plot_height, ChartAxes axes);
  cv::Point at(double x, double y) const;  // data -> canvas pixel
  void dot(double x, double y, const cv::Scalar& c, int radius = 2);
  void cross(double x, double y, const cv::Scalar& c, int size = 4);
  void line(double x0, double y0, double x1, double y1, const cv::Scalar& c, int thickness = 1);
  void text(double x, double y, const std::string& s, const cv::Scalar& c = colour::black);
  /// Tick labels along both axes at the given steps (data units).
  void ticks(double x_step, double y_step);
  void save(const std::filesystem::path& png) const;
  const cv::Mat& canvas() const { return canvas_; }

 private:
  ChartAxes axes_;
  int left_ = 70, top_ = 46, width_, height_;
  cv::Mat canvas_;
};

}  // namespace ctk

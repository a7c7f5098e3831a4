#pragma once
// A chart for report pictures (drawn with cairo, canvas.hpp): data coordinates mapped onto a
// framed plot area, a title, axis labels (the y label reading upwards beside its axis), round
// ticks, a legend, and a PNG written atomically. Used by the calibration and diagnosis reports,
// and by the view planner's pictures.
#include <filesystem>
#include <string>
#include <vector>

#include "ctk/core/canvas.hpp"

namespace ctk {

struct ChartAxes {
  double x0 = 0, x1 = 1, y0 = 0, y1 = 1;  // data range shown, y0 at the bottom
  std::string title, x_label, y_label;
};

/// How a legend entry is marked: as the chart draws dots, crosses and lines.
enum class Mark { dot, cross, line };

struct LegendEntry {
  std::string label;
  cv::Scalar colour;
  Mark mark = Mark::dot;
};

/// A round tick step (1, 2 or 5 times a power of ten) giving about `ticks` ticks over `span`.
double nice_step(double span, int ticks);

/// A tick's label: the shortest of %g, with no "-0".
std::string tick_label(double value);

class Chart {
 public:
  Chart(int plot_width, int plot_height, ChartAxes axes);
  cv::Point2d at(double x, double y) const;  // data -> canvas pixel
  void dot(double x, double y, const cv::Scalar& c, double radius = 2);
  void cross(double x, double y, const cv::Scalar& c, double size = 4);
  /// Cut at the plot's frame; dots and crosses on it are drawn whole.
  void line(double x0, double y0, double x1, double y1, const cv::Scalar& c, double thickness = 1);
  void text(double x, double y, const std::string& s, const cv::Scalar& c = colour::black);
  /// Tick marks and labels along both axes at the given steps (data units).
  void ticks(double x_step, double y_step);
  /// A key in the plot's top-right corner, one entry a line.
  void legend(const std::vector<LegendEntry>& entries);
  void save(const std::filesystem::path& png) const;
  cv::Mat picture() const;  // BGR

 private:
  // Margins about the plot: tick labels and the turned y label left, the title above, tick labels
  // and the x label below.
  static constexpr int left_ = 74, top_ = 34, right_ = 24, bottom_ = 50;
  ChartAxes axes_;
  int width_, height_;
  Canvas canvas_;
};

}  // namespace ctk

#pragma once
// A picture drawn with cairo: antialiased lines, marks and text in a real font (DejaVu Sans through
// fontconfig), on a white ground; pictures pasted in pixel for pixel. Handed to OpenCV as a BGR
// image or written as PNG, atomically. Coordinates are pixels from the top-left corner.
#include <filesystem>
#include <memory>
#include <opencv2/core.hpp>
#include <string>

namespace ctk {

namespace colour {
// BGR, as OpenCV orders them.
const cv::Scalar black(0, 0, 0), grey(160, 160, 160), light(225, 225, 225), red(40, 40, 220), green(60, 170, 60),
    blue(200, 110, 30), orange(30, 140, 240), white(255, 255, 255);
/// From green (0) through yellow to red (1), for values relative to a threshold.
cv::Scalar ramp(double fraction);
}  // namespace colour

/// Where a text's anchor point lies along it.
enum class TextAnchor { left, centre, right };

class Canvas {
 public:
  Canvas(int width, int height);
  ~Canvas();
  Canvas(Canvas&&) noexcept;
  Canvas& operator=(Canvas&&) noexcept;
  Canvas(const Canvas&) = delete;
  Canvas& operator=(const Canvas&) = delete;

  int width() const;
  int height() const;
  void line(cv::Point2d from, cv::Point2d to, const cv::Scalar& colour, double width = 1);
  /// Lines drawn from here on are cut at `box` (a chart's curve leaving its plot), until unclip().
  void clip(const cv::Rect2d& box);
  void unclip();
  void circle(cv::Point2d centre, double radius, const cv::Scalar& colour, bool filled = true);
  void rectangle(const cv::Rect2d& box, const cv::Scalar& colour, bool filled = false, double width = 1);
  /// `text` with its baseline through `at`, which lies at its left end, centre or right end;
  /// `angle_deg` turns it counter-clockwise about `at` (90: reading upwards).
  void text(const std::string& text, cv::Point2d at, double size_px, const cv::Scalar& colour = colour::black,
            TextAnchor anchor = TextAnchor::left, double angle_deg = 0);
  double text_width(const std::string& text, double size_px) const;
  /// An 8-bit grey or BGR picture with its top-left pixel at (x, y), each pixel drawn as a
  /// `zoom` x `zoom` block (no smoothing: a voxel stays a square).
  void paste(const cv::Mat& picture, int x, int y, int zoom = 1);
  cv::Mat bgr() const;
  void save(const std::filesystem::path& png) const;

 private:
  struct Cairo;
  std::unique_ptr<Cairo> cairo_;
};

/// Encodes an 8-bit BGR or grey picture as PNG (libpng) and writes it whole or not at all.
void write_png_atomically(const cv::Mat& picture, const std::filesystem::path& png);

}  // namespace ctk

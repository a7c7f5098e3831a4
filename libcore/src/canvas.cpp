#include "ctk/core/canvas.hpp"

#include <cairo.h>
#include <png.h>

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>
#include <stdexcept>
#include <vector>

#include "ctk/core/atomic_write.hpp"

namespace ctk {

cv::Scalar colour::ramp(double fraction) {
  const double f = std::clamp(fraction, 0.0, 1.0);
  // green (60,170,60) -> yellow (40,200,230) -> red (40,40,220), BGR
  if (f < 0.5) return cv::Scalar(60 - 40 * f, 170 + 60 * f, 60 + 340 * f);
  return cv::Scalar(40, 200 - 320 * (f - 0.5), 230 - 20 * (f - 0.5));
}

// cairo's RGB24 pixels are 32-bit words 0x00RRGGBB: on a little-endian machine the bytes B, G, R,
// unused, which is OpenCV's BGRA; the surface draws straight into the matrix.
struct Canvas::Cairo {
  std::vector<unsigned char> buffer;
  cv::Mat pixels;  // a view of the buffer, rows `stride` bytes apart as cairo wants them
  cairo_surface_t* surface = nullptr;
  cairo_t* cr = nullptr;
  Cairo(int width, int height) {
    if (width < 1 || height < 1)
      throw std::invalid_argument("a picture of " + std::to_string(width) + " x " + std::to_string(height) + " pixels");
    const int stride = cairo_format_stride_for_width(CAIRO_FORMAT_RGB24, width);
    buffer.assign(static_cast<std::size_t>(stride) * static_cast<std::size_t>(height), 255);
    pixels = cv::Mat(height, width, CV_8UC4, buffer.data(), static_cast<std::size_t>(stride));
    surface = cairo_image_surface_create_for_data(pixels.data, CAIRO_FORMAT_RGB24, width, height, stride);
    cr = cairo_create(surface);
    cairo_select_font_face(cr, "DejaVu Sans", CAIRO_FONT_SLANT_NORMAL, CAIRO_FONT_WEIGHT_NORMAL);
  }
  ~Cairo() {
    cairo_destroy(cr);
    cairo_surface_destroy(surface);
  }
  Cairo(const Cairo&) = delete;
  Cairo& operator=(const Cairo&) = delete;
  void colour(const cv::Scalar& c) const { cairo_set_source_rgb(cr, c[2] / 255.0, c[1] / 255.0, c[0] / 255.0); }
};

Canvas::Canvas(int width, int height) : cairo_(std::make_unique<Cairo>(width, height)) {}
Canvas::~Canvas() = default;
Canvas::Canvas(Canvas&&) noexcept = default;
Canvas& Canvas::operator=(Canvas&&) noexcept = default;

int Canvas::width() const { return cairo_->pixels.cols; }
int Canvas::height() const { return cairo_->pixels.rows; }

void Canvas::line(cv::Point2d from, cv::Point2d to, const cv::Scalar& colour, double width) {
  cairo_t* cr = cairo_->cr;
  cairo_->colour(colour);
  cairo_set_line_width(cr, width);
  cairo_move_to(cr, from.x, from.y);
  cairo_line_to(cr, to.x, to.y);
  cairo_stroke(cr);
}

void Canvas::clip(const cv::Rect2d& box) {
  cairo_reset_clip(cairo_->cr);
  cairo_rectangle(cairo_->cr, box.x, box.y, box.width, box.height);
  cairo_clip(cairo_->cr);
}

void Canvas::unclip() { cairo_reset_clip(cairo_->cr); }

void Canvas::circle(cv::Point2d centre, double radius, const cv::Scalar& colour, bool filled) {
  cairo_t* cr = cairo_->cr;
  cairo_->colour(colour);
  cairo_new_sub_path(cr);
  cairo_arc(cr, centre.x, centre.y, radius, 0, 2 * M_PI);
  if (filled) {
    cairo_fill(cr);
  } else {
    cairo_set_line_width(cr, 1);
    cairo_stroke(cr);
  }
}

void Canvas::rectangle(const cv::Rect2d& box, const cv::Scalar& colour, bool filled, double width) {
  cairo_t* cr = cairo_->cr;
  cairo_->colour(colour);
  cairo_rectangle(cr, box.x, box.y, box.width, box.height);
  if (filled) {
    cairo_fill(cr);
  } else {
    cairo_set_line_width(cr, width);
    cairo_stroke(cr);
  }
}

double Canvas::text_width(const std::string& text, double size_px) const {
  cairo_set_font_size(cairo_->cr, size_px);
  cairo_text_extents_t e;
  cairo_text_extents(cairo_->cr, text.c_str(), &e);
  return e.x_advance;
}

void Canvas::text(const std::string& text, cv::Point2d at, double size_px, const cv::Scalar& colour, TextAnchor anchor,
                  double angle_deg) {
  cairo_t* cr = cairo_->cr;
  const double shift = anchor == TextAnchor::left     ? 0.0
                       : anchor == TextAnchor::centre ? -text_width(text, size_px) / 2
                                                      : -text_width(text, size_px);
  cairo_set_font_size(cr, size_px);
  cairo_save(cr);
  cairo_translate(cr, at.x, at.y);
  cairo_rotate(cr, -angle_deg * M_PI / 180);
  cairo_->colour(colour);
  cairo_move_to(cr, shift, 0);
  cairo_show_text(cr, text.c_str());
  cairo_restore(cr);
}

void Canvas::paste(const cv::Mat& picture, int x, int y, int zoom) {
  cv::Mat bgra;
  cv::cvtColor(picture, bgra, picture.channels() == 1 ? cv::COLOR_GRAY2BGRA : cv::COLOR_BGR2BGRA);
  if (zoom > 1) cv::resize(bgra, bgra, cv::Size(), zoom, zoom, cv::INTER_NEAREST);
  const cv::Rect inside = cv::Rect(x, y, bgra.cols, bgra.rows) & cv::Rect(0, 0, width(), height());
  if (inside.empty()) return;
  cairo_surface_flush(cairo_->surface);
  bgra(cv::Rect(inside.x - x, inside.y - y, inside.width, inside.height)).copyTo(cairo_->pixels(inside));
  cairo_surface_mark_dirty(cairo_->surface);
}

cv::Mat Canvas::bgr() const {
  cairo_surface_flush(cairo_->surface);
  cv::Mat out;
  cv::cvtColor(cairo_->pixels, out, cv::COLOR_BGRA2BGR);
  return out;
}

void Canvas::save(const std::filesystem::path& png) const { write_png_atomically(bgr(), png); }

void write_png_atomically(const cv::Mat& picture, const std::filesystem::path& png) {
  if (picture.depth() != CV_8U || (picture.channels() != 1 && picture.channels() != 3))
    throw std::invalid_argument(png.string() + ": a PNG is written from 8-bit grey or BGR pixels");
  const cv::Mat pixels = picture.isContinuous() ? picture : picture.clone();
  png_image image{};
  image.version = PNG_IMAGE_VERSION;
  image.width = static_cast<png_uint_32>(pixels.cols);
  image.height = static_cast<png_uint_32>(pixels.rows);
  image.format = pixels.channels() == 1 ? PNG_FORMAT_GRAY : PNG_FORMAT_BGR;
  png_alloc_size_t size = 0;
  if (!png_image_write_get_memory_size(image, size, 0, pixels.data, 0, nullptr))
    throw std::runtime_error(png.string() + ": cannot encode the PNG: " + image.message);
  std::vector<unsigned char> bytes(size);
  if (!png_image_write_to_memory(&image, bytes.data(), &size, 0, pixels.data, 0, nullptr))
    throw std::runtime_error(png.string() + ": cannot encode the PNG: " + image.message);
  write_file_atomically(png, [&](std::ostream& out) {
    out.write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(size));
  });
}

}  // namespace ctk

#include "ctk/core/image_io.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <fstream>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <utility>

#include "ctk/core/atomic_write.hpp"
#include "ctk/core/canvas.hpp"
#include "ctk/core/error.hpp"
#include "ctk/core/output_set.hpp"
#include "image_codec.hpp"
#include "tiff_reading.hpp"
#include "tiff_writing.hpp"

namespace ctk {

namespace fs = std::filesystem;

namespace {

// Every image ctk writes says which run wrote it, so that a folder mixing two runs is told.
constexpr const char* kWrittenBy = "ctk run ";

// Larger than any detector (4 GB of floats): a header claiming more is damaged or hostile.
constexpr std::size_t kMostPixels = std::size_t{1} << 30;

// Reads the pixels after the header's size has been checked against `expected` (when given), so a
// header claiming 20000 x 20000 costs nothing. Only regular files: a FIFO or a device would hang.
Image read_checked(const fs::path& file, const std::optional<std::pair<int, int>>& expected, std::string* written_by) {
  require_regular_file(file);
  auto check_header = [&](int width, int height, int depth, const std::string& description) {
    if (expected && (width != expected->first || height != expected->second || depth > 1))
      throw InputError(file.string(), "",
                       "image is " + std::to_string(width) + " x " + std::to_string(height) + " pixels, the scan declares " +
                           std::to_string(expected->first) + " x " + std::to_string(expected->second));
    if (width <= 0 || height <= 0 || depth > 1 ||
        static_cast<std::size_t>(width) * static_cast<std::size_t>(height) > kMostPixels)
      throw InputError(file.string(), "",
                       "the header claims " + std::to_string(width) + " x " + std::to_string(height) +
                           (depth > 1 ? " x " + std::to_string(depth) : "") + " pixels: not a projection (damaged header?)");
    if (written_by)
      *written_by =
          description.rfind(kWrittenBy, 0) == 0 ? description.substr(std::string_view(kWrittenBy).size()) : std::string();
  };
  if (auto tiff = PlainTiff::open(file)) {
    check_header(tiff->cols(), tiff->rows(), 1, tiff->description());
    return tiff->read();
  }
  const std::unique_ptr<CodecReader> in = open_with_codec(file, "image");
  const CodecHeader header = in->header();
  check_header(header.width, header.height, header.depth, header.description);
  Image image;
  image.cols = header.width;
  image.rows = header.height;
  image.pixels.resize(static_cast<std::size_t>(header.width) * static_cast<std::size_t>(header.height));
  try {
    in->read_first_channel(image.pixels.data());
  } catch (const std::runtime_error& e) {
    throw InputError(file.string(), "", std::string("cannot read the pixels (truncated or damaged?): ") + e.what());
  }
  // The codec scales integer samples to [0, 1]; keep detector counts instead.
  if (header.integer_bits > 0) {
    const double scale = std::ldexp(1.0, header.integer_bits) - 1.0;
    for (auto& p : image.pixels) p = static_cast<float>(std::round(p * scale));
  }
  return image;
}

}  // namespace

Image read_image(const fs::path& file) { return read_checked(file, std::nullopt, nullptr); }

Image read_image(const fs::path& file, int cols, int rows, std::string* written_by) {
  return read_checked(file, std::make_pair(cols, rows), written_by);
}

namespace {

// TIFFs through libtiff (tiff_writing.hpp), other formats through the codec module.
void write_single_image(int cols, int rows, TiffPage::Samples samples, const void* pixels, const fs::path& file) {
  const std::string description = kWrittenBy + this_run_id();
  if (has_tiff_extension(file)) {
    const TiffPage page{static_cast<std::uint32_t>(cols), static_cast<std::uint32_t>(rows), samples, pixels, description, {}, {}};
    write_tiff_atomically(file, [&](TIFF* out) { write_tiff_page(out, page, file); });
    return;
  }
  write_path_atomically(file, [&](const fs::path& tmp) {
    try {
      image_codec().write(file, tmp, cols, rows, samples == TiffPage::Samples::uint16 ? 16 : 0, pixels, description);
    } catch (const std::runtime_error& e) {
      throw std::runtime_error(file.string() + ": " + e.what());
    }
  });
}

}  // namespace

void write_image_float(const Image& image, const fs::path& file) {
  write_single_image(image.cols, image.rows, TiffPage::Samples::float32, image.pixels.data(), file);
}

void write_image_uint16(const Image& counts, const fs::path& file) {
  std::vector<std::uint16_t> pixels(counts.pixels.size());
  std::transform(counts.pixels.begin(), counts.pixels.end(), pixels.begin(),
                 [](float c) { return static_cast<std::uint16_t>(std::lround(std::clamp(c, 0.0f, 65535.0f))); });
  write_single_image(counts.cols, counts.rows, TiffPage::Samples::uint16, pixels.data(), file);
}

Image binned_image(const Image& image, int b) {
  if (b < 1 || b > image.cols || b > image.rows)
    throw std::invalid_argument("binning factor " + std::to_string(b) + " does not fit a " + std::to_string(image.cols) + " x " +
                                std::to_string(image.rows) + " image");
  const int cols = image.cols / b, rows = image.rows / b;
  Image out{cols, rows, std::vector<float>(static_cast<std::size_t>(cols) * static_cast<std::size_t>(rows), 0.0f)};
  const float scale = 1.0f / static_cast<float>(b * b);
  for (int r = 0; r < rows * b; ++r)
    for (int c = 0; c < cols * b; ++c)
      out.pixels[static_cast<std::size_t>(r / b) * static_cast<std::size_t>(cols) + static_cast<std::size_t>(c / b)] +=
          scale * image.pixels[static_cast<std::size_t>(r) * static_cast<std::size_t>(image.cols) + static_cast<std::size_t>(c)];
  return out;
}

float preview_ceiling(const Volume& volume) {
  if (volume.data.empty()) return 1e-6f;
  std::vector<float> sorted(volume.data.begin(), volume.data.end());
  const std::size_t hi = static_cast<std::size_t>(0.999 * static_cast<double>(sorted.size() - 1));
  std::nth_element(sorted.begin(), sorted.begin() + static_cast<std::ptrdiff_t>(hi), sorted.end());
  return std::max(sorted[hi], 1e-6f);
}

void write_slice_png(const Volume& v, int axis, int index, float low, float high, const fs::path& file) {
  const auto& s = v.layout.size;
  const int w = axis == 0 ? s[1] : s[0], h = axis == 2 ? s[1] : s[2];
  cv::Mat grey(h, w, CV_8UC1);
  for (int r = 0; r < h; ++r)
    for (int c = 0; c < w; ++c) {
      const int z = h - 1 - r;  // coronal and sagittal slices with z up, as the scanner shows them
      const float value = axis == 0 ? v.at(index, c, z) : axis == 1 ? v.at(c, index, z) : v.at(c, r, index);
      const float g = std::clamp((value - low) / std::max(high - low, 1e-30f), 0.0f, 1.0f);
      grey.at<unsigned char>(r, c) = static_cast<unsigned char>(std::lround(255.0f * g));
    }
  write_png_atomically(grey, file);
}

}  // namespace ctk

#include "ctk/core/image_io.hpp"

#include <OpenImageIO/imageio.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <fstream>
#include <optional>
#include <stdexcept>
#include <string>
#include <utility>

#include "ctk/core/atomic_write.hpp"
#include "ctk/core/error.hpp"
#include "ctk/core/output_set.hpp"
#include "tiff_reading.hpp"

namespace ctk {

namespace fs = std::filesystem;
using OIIO::ImageInput;
using OIIO::ImageOutput;
using OIIO::ImageSpec;
using OIIO::TypeDesc;

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
  auto in = ImageInput::open(file.string());
  if (!in) throw InputError(file.string(), "", "cannot read the image: " + OIIO::geterror());
  const ImageSpec& spec = in->spec();
  check_header(spec.width, spec.height, spec.depth, spec.get_string_attribute("ImageDescription"));
  Image image;
  image.cols = spec.width;
  image.rows = spec.height;
  image.pixels.resize(static_cast<std::size_t>(spec.width) * static_cast<std::size_t>(spec.height));
  // A truncated file may read "successfully" with an error recorded: check both.
  if (!in->read_image(0, 0, 0, 1, TypeDesc::FLOAT, image.pixels.data()) || in->has_error())
    throw InputError(file.string(), "", "cannot read the pixels (truncated or damaged?): " + in->geterror());
  // OIIO scales integer types to [0, 1] when converting to float; keep detector counts instead.
  const double scale = spec.format == TypeDesc::UINT16   ? 65535.0
                       : spec.format == TypeDesc::UINT8  ? 255.0
                       : spec.format == TypeDesc::UINT32 ? 4294967295.0
                                                         : 1.0;
  if (scale != 1.0)
    for (auto& p : image.pixels) p = static_cast<float>(std::round(p * scale));
  return image;
}

}  // namespace

Image read_image(const fs::path& file) { return read_checked(file, std::nullopt, nullptr); }

Image read_image(const fs::path& file, int cols, int rows, std::string* written_by) {
  return read_checked(file, std::make_pair(cols, rows), written_by);
}

namespace {

void write_single_image(int cols, int rows, TypeDesc type, const void* pixels, const fs::path& file) {
  write_path_atomically(file, [&](const fs::path& tmp) {
    auto out = ImageOutput::create(file.string());
    if (!out) throw std::runtime_error(file.string() + ": no writer for this format: " + OIIO::geterror());
    ImageSpec spec(cols, rows, 1, type);
    spec.attribute("ImageDescription", kWrittenBy + this_run_id());
    if (!out->open(tmp.string(), spec) || !out->write_image(type, pixels) || !out->close())
      throw std::runtime_error(file.string() + ": write failed: " + out->geterror());
  });
}

}  // namespace

void write_image_float(const Image& image, const fs::path& file) {
  write_single_image(image.cols, image.rows, TypeDesc::FLOAT, image.pixels.data(), file);
}

void write_image_uint16(const Image& counts, const fs::path& file) {
  std::vector<std::uint16_t> pixels(counts.pixels.size());
  std::transform(counts.pixels.begin(), counts.pixels.end(), pixels.begin(),
                 [](float c) { return static_cast<std::uint16_t>(std::lround(std::clamp(c, 0.0f, 65535.0f))); });
  write_single_image(counts.cols, counts.rows, TypeDesc::UINT16, pixels.data(), file);
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
  std::vector<unsigned char> pixels(static_cast<std::size_t>(w) * static_cast<std::size_t>(h));
  for (int r = 0; r < h; ++r)
    for (int c = 0; c < w; ++c) {
      const int z = h - 1 - r;  // coronal and sagittal slices with z up, as the scanner shows them
      const float value = axis == 0 ? v.at(index, c, z) : axis == 1 ? v.at(c, index, z) : v.at(c, r, index);
      const float g = std::clamp((value - low) / std::max(high - low, 1e-30f), 0.0f, 1.0f);
      pixels[static_cast<std::size_t>(r) * static_cast<std::size_t>(w) + static_cast<std::size_t>(c)] =
          static_cast<unsigned char>(std::lround(255.0f * g));
    }
  write_path_atomically(file, [&](const fs::path& tmp) {
    auto out = ImageOutput::create(file.string());
    if (!out || !out->open(tmp.string(), ImageSpec(w, h, 1, TypeDesc::UINT8)) ||
        !out->write_image(TypeDesc::UINT8, pixels.data()) || !out->close())
      throw std::runtime_error(file.string() + ": cannot write PNG");
  });
}

}  // namespace ctk

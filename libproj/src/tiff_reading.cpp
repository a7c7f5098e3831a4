#include "tiff_reading.hpp"

#include <tiffio.h>

#include <algorithm>
#include <cctype>
#include <cstdarg>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <memory>
#include <vector>

#include "ctk/geom/error.hpp"

namespace ctk {

namespace fs = std::filesystem;

namespace {

// libtiff's messages are kept for the InputError instead of going to stderr.
int keep_message(TIFF*, void* user_data, const char* module, const char* format, va_list args) {
  char text[512];
  std::vsnprintf(text, sizeof text, format, args);
  auto& kept = *static_cast<std::string*>(user_data);
  if (kept.empty()) kept = std::string(module ? module : "libtiff") + ": " + text;
  return 1;
}

int ignore_message(TIFF*, void*, const char*, const char*, va_list) { return 1; }

bool has_tiff_extension(const fs::path& file) {
  std::string ext = file.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return ext == ".tif" || ext == ".tiff";
}

template <typename Sample>
void widen(const unsigned char* bytes, std::size_t count, float* out) {
  for (std::size_t i = 0; i < count; ++i) {
    Sample s;
    std::memcpy(&s, bytes + i * sizeof(Sample), sizeof(Sample));
    out[i] = static_cast<float>(s);
  }
}

}  // namespace

std::optional<TiffImage> read_plain_tiff(const fs::path& file, const std::optional<std::pair<int, int>>& expected,
                                         std::size_t most_pixels) {
  if (!has_tiff_extension(file)) return std::nullopt;
  std::string error;
  std::unique_ptr<TIFFOpenOptions, void (*)(TIFFOpenOptions*)> options(TIFFOpenOptionsAlloc(), TIFFOpenOptionsFree);
  TIFFOpenOptionsSetErrorHandlerExtR(options.get(), keep_message, &error);
  TIFFOpenOptionsSetWarningHandlerExtR(options.get(), ignore_message, nullptr);
  std::unique_ptr<TIFF, void (*)(TIFF*)> tif(TIFFOpenExt(file.c_str(), "r", options.get()), TIFFClose);
  if (!tif) return std::nullopt;

  std::uint32_t cols = 0, rows = 0;
  std::uint16_t samples = 1, bits = 1, format = SAMPLEFORMAT_UINT, planar = PLANARCONFIG_CONTIG,
                photometric = PHOTOMETRIC_MINISBLACK;
  TIFFGetField(tif.get(), TIFFTAG_IMAGEWIDTH, &cols);
  TIFFGetField(tif.get(), TIFFTAG_IMAGELENGTH, &rows);
  TIFFGetFieldDefaulted(tif.get(), TIFFTAG_SAMPLESPERPIXEL, &samples);
  TIFFGetFieldDefaulted(tif.get(), TIFFTAG_BITSPERSAMPLE, &bits);
  TIFFGetFieldDefaulted(tif.get(), TIFFTAG_SAMPLEFORMAT, &format);
  TIFFGetFieldDefaulted(tif.get(), TIFFTAG_PLANARCONFIG, &planar);
  TIFFGetField(tif.get(), TIFFTAG_PHOTOMETRIC, &photometric);
  const bool plain_samples =
      (format == SAMPLEFORMAT_UINT && (bits == 8 || bits == 16 || bits == 32)) || (format == SAMPLEFORMAT_IEEEFP && bits == 32);
  if (TIFFIsTiled(tif.get()) || samples != 1 || planar != PLANARCONFIG_CONTIG || photometric != PHOTOMETRIC_MINISBLACK ||
      !plain_samples || cols == 0 || rows == 0)
    return std::nullopt;

  if (expected && (cols != static_cast<std::uint32_t>(expected->first) || rows != static_cast<std::uint32_t>(expected->second)))
    throw InputError(file.string(), "",
                     "image is " + std::to_string(cols) + " x " + std::to_string(rows) + " pixels, the scan declares " +
                         std::to_string(expected->first) + " x " + std::to_string(expected->second));
  if (static_cast<std::size_t>(cols) * rows > most_pixels) return std::nullopt;  // the general reader words the refusal

  TiffImage out;
  if (char* description = nullptr; TIFFGetField(tif.get(), TIFFTAG_IMAGEDESCRIPTION, &description) && description)
    out.description = description;
  out.image.cols = static_cast<int>(cols);
  out.image.rows = static_cast<int>(rows);
  out.image.pixels.resize(static_cast<std::size_t>(cols) * rows);
  const std::size_t bytes_per_sample = bits / 8, row_bytes = bytes_per_sample * cols;
  std::uint32_t rows_per_strip = rows;
  TIFFGetFieldDefaulted(tif.get(), TIFFTAG_ROWSPERSTRIP, &rows_per_strip);
  rows_per_strip = std::clamp<std::uint32_t>(rows_per_strip, 1, rows);
  std::vector<unsigned char> strip(row_bytes * rows_per_strip);
  const auto fail = [&](const std::string& what) {
    return InputError(file.string(), "",
                      "cannot read the pixels (truncated or damaged?): " + what + (error.empty() ? "" : " (" + error + ")"));
  };
  for (std::uint32_t row = 0, index = 0; row < rows; row += rows_per_strip, ++index) {
    const std::uint32_t strip_rows = std::min(rows_per_strip, rows - row);
    const auto want = static_cast<tmsize_t>(row_bytes * strip_rows);
    if (TIFFReadEncodedStrip(tif.get(), index, strip.data(), want) != want) throw fail("strip " + std::to_string(index));
    float* dst = out.image.pixels.data() + static_cast<std::size_t>(row) * cols;
    const std::size_t count = static_cast<std::size_t>(strip_rows) * cols;
    if (format == SAMPLEFORMAT_IEEEFP)
      widen<float>(strip.data(), count, dst);
    else if (bits == 8)
      widen<std::uint8_t>(strip.data(), count, dst);
    else if (bits == 16)
      widen<std::uint16_t>(strip.data(), count, dst);
    else
      widen<std::uint32_t>(strip.data(), count, dst);
  }
  return out;
}

}  // namespace ctk

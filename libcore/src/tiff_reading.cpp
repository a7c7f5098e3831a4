#include "tiff_reading.hpp"

#include <algorithm>
#include <cctype>
#include <cstdarg>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <memory>
#include <vector>

#include "ctk/core/error.hpp"

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

template <typename Sample>
void widen(const unsigned char* bytes, std::size_t count, float* out) {
  for (std::size_t i = 0; i < count; ++i) {
    Sample s;
    std::memcpy(&s, bytes + i * sizeof(Sample), sizeof(Sample));
    out[i] = static_cast<float>(s);
  }
}

}  // namespace

bool has_tiff_extension(const fs::path& file) {
  std::string ext = file.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return ext == ".tif" || ext == ".tiff";
}

std::optional<PlainTiff> PlainTiff::open(const fs::path& file) {
  if (!has_tiff_extension(file)) return std::nullopt;
  PlainTiff t;
  t.file_ = file;
  t.error_ = std::make_shared<std::string>();
  std::unique_ptr<TIFFOpenOptions, void (*)(TIFFOpenOptions*)> options(TIFFOpenOptionsAlloc(), TIFFOpenOptionsFree);
  TIFFOpenOptionsSetErrorHandlerExtR(options.get(), keep_message, t.error_.get());
  TIFFOpenOptionsSetWarningHandlerExtR(options.get(), ignore_message, nullptr);
  t.tif_ = std::shared_ptr<TIFF>(TIFFOpenExt(file.c_str(), "r", options.get()), [](TIFF* tif) {
    if (tif) TIFFClose(tif);
  });
  if (!t.tif_) return std::nullopt;
  TIFF* tif = t.tif_.get();
  std::uint16_t samples = 1, planar = PLANARCONFIG_CONTIG, photometric = PHOTOMETRIC_MINISBLACK;
  t.bits_ = 1;
  t.format_ = SAMPLEFORMAT_UINT;
  TIFFGetField(tif, TIFFTAG_IMAGEWIDTH, &t.cols_);
  TIFFGetField(tif, TIFFTAG_IMAGELENGTH, &t.rows_);
  TIFFGetFieldDefaulted(tif, TIFFTAG_SAMPLESPERPIXEL, &samples);
  TIFFGetFieldDefaulted(tif, TIFFTAG_BITSPERSAMPLE, &t.bits_);
  TIFFGetFieldDefaulted(tif, TIFFTAG_SAMPLEFORMAT, &t.format_);
  TIFFGetFieldDefaulted(tif, TIFFTAG_PLANARCONFIG, &planar);
  TIFFGetField(tif, TIFFTAG_PHOTOMETRIC, &photometric);
  const bool plain_samples = (t.format_ == SAMPLEFORMAT_UINT && (t.bits_ == 8 || t.bits_ == 16 || t.bits_ == 32)) ||
                             (t.format_ == SAMPLEFORMAT_IEEEFP && t.bits_ == 32);
  if (TIFFIsTiled(tif) || samples != 1 || planar != PLANARCONFIG_CONTIG || photometric != PHOTOMETRIC_MINISBLACK ||
      !plain_samples || t.cols_ == 0 || t.rows_ == 0 || t.cols_ > (1u << 30) || t.rows_ > (1u << 30))
    return std::nullopt;
  if (char* description = nullptr; TIFFGetField(tif, TIFFTAG_IMAGEDESCRIPTION, &description) && description)
    t.description_ = description;
  return t;
}

Image PlainTiff::read() {
  TIFF* tif = tif_.get();
  Image out;
  out.cols = cols();
  out.rows = rows();
  out.pixels.resize(static_cast<std::size_t>(cols_) * rows_);
  const std::size_t row_bytes = static_cast<std::size_t>(bits_ / 8) * cols_;
  std::uint32_t rows_per_strip = rows_;
  TIFFGetFieldDefaulted(tif, TIFFTAG_ROWSPERSTRIP, &rows_per_strip);
  rows_per_strip = std::clamp<std::uint32_t>(rows_per_strip, 1, rows_);
  std::vector<unsigned char> strip(row_bytes * rows_per_strip);
  for (std::uint32_t row = 0, index = 0; row < rows_; row += rows_per_strip, ++index) {
    const std::uint32_t strip_rows = std::min(rows_per_strip, rows_ - row);
    const auto want = static_cast<tmsize_t>(row_bytes * strip_rows);
    if (TIFFReadEncodedStrip(tif, index, strip.data(), want) != want)
      throw InputError(file_.string(), "",
                       "cannot read the pixels (truncated or damaged?): strip " + std::to_string(index) +
                           (error_->empty() ? "" : " (" + *error_ + ")"));
    float* dst = out.pixels.data() + static_cast<std::size_t>(row) * cols_;
    const std::size_t count = static_cast<std::size_t>(strip_rows) * cols_;
    if (format_ == SAMPLEFORMAT_IEEEFP)
      widen<float>(strip.data(), count, dst);
    else if (bits_ == 8)
      widen<std::uint8_t>(strip.data(), count, dst);
    else if (bits_ == 16)
      widen<std::uint16_t>(strip.data(), count, dst);
    else
      widen<std::uint32_t>(strip.data(), count, dst);
  }
  return out;
}

}  // namespace ctk

#pragma once
// One page of a strip TIFF written through libtiff: deflate-compressed, a horizontal predictor on
// integer samples only. Readers without codec libraries of their own (Python's tifffile without
// imagecodecs, as Debian 12 ships it) decode these; the floating-point predictor OpenImageIO puts
// on compressed floats they cannot.
#include <tiffio.h>

#include <cstdint>
#include <filesystem>
#include <functional>
#include <optional>
#include <string>

namespace ctk {

struct TiffPage {
  std::uint32_t cols = 0, rows = 0;
  enum class Samples { uint16, float32 } samples = Samples::float32;
  const void* pixels = nullptr;                              // rows x cols samples, row 0 first
  std::string description;                                   // ImageDescription ("" writes none)
  std::optional<std::pair<double, double>> pixels_per_unit;  // X and Y resolution (unit: none)
  std::optional<std::pair<int, int>> page_of;                // page number and page count of a stack
};

/// Writes `page` as the next directory of `tiff`; std::runtime_error naming `file` when it fails.
void write_tiff_page(TIFF* tiff, const TiffPage& page, const std::filesystem::path& file);

/// A TIFF written atomically (write_path_atomically): `write_pages` writes its pages.
void write_tiff_atomically(const std::filesystem::path& file, const std::function<void(TIFF*)>& write_pages);

}  // namespace ctk

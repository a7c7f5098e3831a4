#pragma once
// Single-channel strip TIFFs, what detectors write, read straight through libtiff: it decodes
// deflate with libdeflate where OpenImageIO uses zlib, and the samples become floats in one pass
// (120 deflate TIFFs of 720 x 720 x 16 bit: 0.62 s against 1.15 s through OpenImageIO on one
// Zen 5 core). Every other layout is left to OpenImageIO.
#include <filesystem>
#include <optional>
#include <string>
#include <utility>

#include "ctk/proj/image_io.hpp"

namespace ctk {

struct TiffImage {
  Image image;
  std::string description;  // the ImageDescription tag ("" when absent)
};

/// The first (only) channel of a strip TIFF with one sample per pixel, 8/16/32-bit unsigned or
/// 32-bit float, as counts (integer samples keep their values). `std::nullopt` when the file is
/// not such a TIFF (or libtiff cannot open it): the caller reads it the general way. The size is
/// checked against `expected` before any pixel is allocated (InputError naming the file), and a
/// strip that does not decode is an InputError naming it too.
std::optional<TiffImage> read_plain_tiff(const std::filesystem::path& file, const std::optional<std::pair<int, int>>& expected,
                                         std::size_t most_pixels);

}  // namespace ctk

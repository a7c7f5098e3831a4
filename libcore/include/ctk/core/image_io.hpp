#pragma once
// Image files through OpenImageIO: projections in (TIFF uint16/uint32/float, EXR) and out, a
// volume's slices as PNG previews (volume files: volume_file.hpp). Every output is written atomically.
#include <filesystem>
#include <string>
#include <vector>

#include "ctk/core/projection_stack.hpp"
#include "ctk/core/volume.hpp"

namespace ctk {

struct Image {
  int cols = 0, rows = 0;
  std::vector<float> pixels;  // first channel, row-major, row 0 first
};

/// Reads the first channel of an image as float (integer types keep their count values).
/// Throws InputError naming the file when it is missing, truncated or not an image.
Image read_image(const std::filesystem::path& file);
/// Same, and the size must be cols x rows (InputError otherwise).
/// `written_by` (optional) receives the ctk run that wrote the file (every image ctk writes names
/// its run in its ImageDescription), or "" when no ctk run did.
Image read_image(const std::filesystem::path& file, int cols, int rows, std::string* written_by = nullptr);

void write_image_float(const Image& image, const std::filesystem::path& file);  // TIFF/EXR by extension
/// Detector counts as a 16-bit TIFF: values rounded and clamped to 0 .. 65535.
void write_image_uint16(const Image& counts, const std::filesystem::path& file);

/// The mean of each b x b block (a last partial row or column dropped): binned counts give the
/// same line integrals as summed ones, since flat and dark are binned alike. Throws
/// std::invalid_argument for a factor below 1 or larger than the image.
Image binned_image(const Image& image, int factor);

/// The grey level previews map to white: the 99.9th percentile of the voxels (a few hot voxels
/// must not darken the picture), at least 1e-6.
float preview_ceiling(const Volume& volume);
/// Slice `index` across `axis` (0: x, 1: y, 2: z), one pixel per voxel, grey levels linear from `low`
/// to `high`; coronal and sagittal slices (axes 0 and 1) with z up. Labelled previews: slice_preview.hpp.
void write_slice_png(const Volume& volume, int axis, int index, float low, float high, const std::filesystem::path& file);

}  // namespace ctk

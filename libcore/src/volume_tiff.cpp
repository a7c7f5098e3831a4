// A volume as a multi-page float32 TIFF, one page per z slice, readable by Fiji as a stack (and by
// readers without codecs of their own: deflate, no predictor): the
// first page's ImageDescription is ImageJ's ("ImageJ=", images, slices, unit, spacing) with ctk's
// exact voxel size and origin as two more lines (ImageJ keeps only x, y resolution and z spacing).
#include <OpenImageIO/imageio.h>
#include <tiffio.h>

#include <algorithm>
#include <cstdint>
#include <memory>
#include <sstream>
#include <vector>

#include "ctk/core/atomic_write.hpp"
#include "ctk/core/error.hpp"
#include "volume_formats.hpp"

namespace ctk::volume_formats {

namespace fs = std::filesystem;
using OIIO::ImageInput;
using OIIO::ImageSpec;
using OIIO::TypeDesc;

void write_tiff(const VolumeSlabs& v, const fs::path& file) {
  const auto& l = v.layout;
  std::ostringstream description;
  description.precision(17);
  description << "ImageJ=1.53t\nimages=" << l.size[2] << "\nslices=" << l.size[2] << "\nunit=mm\nspacing=" << l.voxel_mm.z()
              << "\nloop=false\nctk_voxel_mm=" << l.voxel_mm.x() << " " << l.voxel_mm.y() << " " << l.voxel_mm.z()
              << "\nctk_origin_mm=" << l.origin_mm.x() << " " << l.origin_mm.y() << " " << l.origin_mm.z() << "\n";
  const std::string text = description.str();
  // libtiff directly, deflate without a predictor: OpenImageIO adds the floating-point predictor
  // to compressed floats, which readers without a codec library of their own (Python's tifffile
  // without imagecodecs, as Debian 12 ships it) cannot decode.
  write_path_atomically(file, [&](const fs::path& tmp) {
    const std::unique_ptr<TIFF, void (*)(TIFF*)> out(TIFFOpen(tmp.c_str(), "w"), TIFFClose);
    if (!out) throw std::runtime_error(file.string() + ": cannot open for writing");
    const auto cols = static_cast<std::uint32_t>(l.size[0]), rows = static_cast<std::uint32_t>(l.size[1]);
    const std::size_t slice = static_cast<std::size_t>(cols) * rows;
    // Strips of about 256 KiB: small enough to decode one row band at a time, large enough to compress.
    const std::uint32_t rows_per_strip = std::max<std::uint32_t>(1, static_cast<std::uint32_t>(262144 / (4 * std::size_t{cols})));
    std::vector<float> plane(slice);
    int z = 0;
    for (std::size_t k = 0; k < v.planes.size(); ++k) {
      const std::span<const float> slab = checked_slab(v, static_cast<int>(k));
      for (int p = 0; p < v.planes[k]; ++p, ++z) {
        TIFF* t = out.get();
        TIFFSetField(t, TIFFTAG_IMAGEWIDTH, cols);
        TIFFSetField(t, TIFFTAG_IMAGELENGTH, rows);
        TIFFSetField(t, TIFFTAG_BITSPERSAMPLE, 32);
        TIFFSetField(t, TIFFTAG_SAMPLEFORMAT, SAMPLEFORMAT_IEEEFP);
        TIFFSetField(t, TIFFTAG_SAMPLESPERPIXEL, 1);
        TIFFSetField(t, TIFFTAG_PHOTOMETRIC, PHOTOMETRIC_MINISBLACK);
        TIFFSetField(t, TIFFTAG_PLANARCONFIG, PLANARCONFIG_CONTIG);
        TIFFSetField(t, TIFFTAG_COMPRESSION, COMPRESSION_ADOBE_DEFLATE);
        TIFFSetField(t, TIFFTAG_PREDICTOR, PREDICTOR_NONE);
        TIFFSetField(t, TIFFTAG_ROWSPERSTRIP, rows_per_strip);
        TIFFSetField(t, TIFFTAG_XRESOLUTION, static_cast<float>(1 / l.voxel_mm.x()));
        TIFFSetField(t, TIFFTAG_YRESOLUTION, static_cast<float>(1 / l.voxel_mm.y()));
        TIFFSetField(t, TIFFTAG_RESOLUTIONUNIT, RESUNIT_NONE);
        TIFFSetField(t, TIFFTAG_SUBFILETYPE, FILETYPE_PAGE);
        TIFFSetField(t, TIFFTAG_PAGENUMBER, static_cast<std::uint16_t>(std::min(z, 65535)),
                     static_cast<std::uint16_t>(std::min(l.size[2], 65535)));
        if (z == 0) TIFFSetField(t, TIFFTAG_IMAGEDESCRIPTION, text.c_str());
        std::copy_n(slab.data() + static_cast<std::size_t>(p) * slice, slice, plane.begin());
        for (std::uint32_t row = 0; row < rows; row += rows_per_strip) {
          const std::uint32_t count = std::min(rows_per_strip, rows - row);
          if (TIFFWriteEncodedStrip(t, TIFFComputeStrip(t, row, 0), plane.data() + std::size_t{row} * cols,
                                    static_cast<tmsize_t>(std::size_t{count} * cols * sizeof(float))) < 0)
            throw std::runtime_error(file.string() + ": cannot write page " + std::to_string(z) + " (disk full?)");
        }
        if (!TIFFWriteDirectory(t))
          throw std::runtime_error(file.string() + ": cannot write page " + std::to_string(z) + " (disk full?)");
      }
    }
  });
}

Volume read_tiff(const fs::path& file) {
  auto in = ImageInput::open(file.string());
  if (!in) throw InputError(file.string(), "", "cannot read the TIFF: " + OIIO::geterror());
  const ImageSpec first = in->spec();
  if (first.nchannels != 1 || first.depth > 1)
    throw InputError(file.string(), "page 0", "expected one channel per page, one page per z slice");
  // The page count, each page the first's size.
  int pages = 0;
  while (in->seek_subimage(pages, 0)) {
    if (in->spec().width != first.width || in->spec().height != first.height || in->spec().nchannels != 1)
      throw InputError(file.string(), "page " + std::to_string(pages),
                       "is " + std::to_string(in->spec().width) + " x " + std::to_string(in->spec().height) + " pixels, page 0 " +
                           std::to_string(first.width) + " x " + std::to_string(first.height));
    ++pages;
  }
  VolumeLayout l;
  l.size = {first.width, first.height, pages};
  const std::string description = first.get_string_attribute("ImageDescription");
  std::istringstream lines(description);
  std::string line;
  bool have_origin = false;
  while (std::getline(lines, line)) {
    if (line.rfind("ctk_voxel_mm=", 0) == 0) {
      l.voxel_mm = parse_vector3(line.substr(13), file, "ImageDescription ctk_voxel_mm");
    } else if (line.rfind("ctk_origin_mm=", 0) == 0) {
      l.origin_mm = parse_vector3(line.substr(14), file, "ImageDescription ctk_origin_mm");
      have_origin = true;
    }
  }
  if (!have_origin) l.origin_mm = VolumeLayout::centred(l.size, l.voxel_mm).origin_mm;
  check_layout(l, file, "page size");
  Volume v(l);
  const std::size_t slice = static_cast<std::size_t>(l.size[0]) * static_cast<std::size_t>(l.size[1]);
  for (int z = 0; z < pages; ++z)
    if (!in->seek_subimage(z, 0) ||
        !in->read_image(z, 0, 0, 1, TypeDesc::FLOAT, v.data.data() + static_cast<std::size_t>(z) * slice))
      throw InputError(file.string(), "page " + std::to_string(z), "cannot read: " + in->geterror());
  return v;
}

}  // namespace ctk::volume_formats

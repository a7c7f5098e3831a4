// A volume as a multi-page float32 TIFF, one page per z slice, readable by Fiji as a stack (and by
// readers without codecs of their own: deflate, no predictor): the
// first page's ImageDescription is ImageJ's ("ImageJ=", images, slices, unit, spacing) with ctk's
// exact voxel size and origin as two more lines (ImageJ keeps only x, y resolution and z spacing).
#include <tiffio.h>

#include <algorithm>
#include <cstdint>
#include <memory>
#include <sstream>
#include <vector>

#include "ctk/core/atomic_write.hpp"
#include "ctk/core/error.hpp"
#include "image_codec.hpp"
#include "tiff_writing.hpp"
#include "volume_formats.hpp"

namespace ctk::volume_formats {

namespace fs = std::filesystem;

void write_tiff(const VolumeSlabs& v, const fs::path& file) {
  const auto& l = v.layout;
  std::ostringstream description;
  description.precision(17);
  description << "ImageJ=1.53t\nimages=" << l.size[2] << "\nslices=" << l.size[2] << "\nunit=mm\nspacing=" << l.voxel_mm.z()
              << "\nloop=false\nctk_voxel_mm=" << l.voxel_mm.x() << " " << l.voxel_mm.y() << " " << l.voxel_mm.z()
              << "\nctk_origin_mm=" << l.origin_mm.x() << " " << l.origin_mm.y() << " " << l.origin_mm.z() << "\n";
  const std::string text = description.str();
  write_tiff_atomically(file, [&](TIFF* out) {
    TiffPage page;
    page.cols = static_cast<std::uint32_t>(l.size[0]);
    page.rows = static_cast<std::uint32_t>(l.size[1]);
    page.pixels_per_unit = std::make_pair(1 / l.voxel_mm.x(), 1 / l.voxel_mm.y());
    const std::size_t slice = std::size_t{page.cols} * page.rows;
    int z = 0;
    for (std::size_t k = 0; k < v.planes.size(); ++k) {
      const std::span<const float> slab = checked_slab(v, static_cast<int>(k));
      for (int p = 0; p < v.planes[k]; ++p, ++z) {
        page.pixels = slab.data() + static_cast<std::size_t>(p) * slice;
        page.page_of = std::make_pair(z, l.size[2]);
        page.description = z == 0 ? text : std::string();
        write_tiff_page(out, page, file);
      }
    }
  });
}

Volume read_tiff(const fs::path& file) {
  const std::unique_ptr<CodecReader> in = open_with_codec(file, "TIFF");
  const CodecHeader first = in->header();
  if (first.channels != 1 || first.depth > 1)
    throw InputError(file.string(), "page 0", "expected one channel per page, one page per z slice");
  // The page count, each page the first's size.
  int pages = 0;
  while (in->seek(pages)) {
    const CodecHeader h = in->header();
    if (h.width != first.width || h.height != first.height || h.channels != 1)
      throw InputError(file.string(), "page " + std::to_string(pages),
                       "is " + std::to_string(h.width) + " x " + std::to_string(h.height) + " pixels, page 0 " +
                           std::to_string(first.width) + " x " + std::to_string(first.height));
    ++pages;
  }
  VolumeLayout l;
  l.size = {first.width, first.height, pages};
  std::istringstream lines(first.description);
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
  for (int z = 0; z < pages; ++z) {
    try {
      if (!in->seek(z)) throw std::runtime_error("the page is gone");
      in->read_first_channel(v.data.data() + static_cast<std::size_t>(z) * slice);
    } catch (const std::runtime_error& e) {
      throw InputError(file.string(), "page " + std::to_string(z), std::string("cannot read: ") + e.what());
    }
  }
  return v;
}

}  // namespace ctk::volume_formats

// A volume as a multi-page float32 TIFF, one page per z slice, readable by Fiji as a stack: the
// first page's ImageDescription is ImageJ's ("ImageJ=", images, slices, unit, spacing) with ctk's
// exact voxel size and origin as two more lines (ImageJ keeps only x, y resolution and z spacing).
#include <OpenImageIO/imageio.h>

#include <sstream>

#include "ctk/core/atomic_write.hpp"
#include "ctk/core/error.hpp"
#include "volume_formats.hpp"

namespace ctk::volume_formats {

namespace fs = std::filesystem;
using OIIO::ImageInput;
using OIIO::ImageOutput;
using OIIO::ImageSpec;
using OIIO::TypeDesc;

void write_tiff(const VolumeSlabs& v, const fs::path& file) {
  const auto& l = v.layout;
  std::ostringstream description;
  description.precision(17);
  description << "ImageJ=1.53t\nimages=" << l.size[2] << "\nslices=" << l.size[2] << "\nunit=mm\nspacing=" << l.voxel_mm.z()
              << "\nloop=false\nctk_voxel_mm=" << l.voxel_mm.x() << " " << l.voxel_mm.y() << " " << l.voxel_mm.z()
              << "\nctk_origin_mm=" << l.origin_mm.x() << " " << l.origin_mm.y() << " " << l.origin_mm.z() << "\n";
  write_path_atomically(file, [&](const fs::path& tmp) {
    auto out = ImageOutput::create(file.string());
    if (!out || !out->supports("multiimage")) throw std::runtime_error(file.string() + ": cannot write multi-page TIFF");
    const int nz = l.size[2];
    std::vector<ImageSpec> specs(static_cast<std::size_t>(nz), ImageSpec(l.size[0], l.size[1], 1, TypeDesc::FLOAT));
    for (ImageSpec& spec : specs) {
      spec.attribute("XResolution", static_cast<float>(1 / l.voxel_mm.x()));
      spec.attribute("YResolution", static_cast<float>(1 / l.voxel_mm.y()));
      spec.attribute("ResolutionUnit", "none");
    }
    specs[0].attribute("ImageDescription", description.str());
    if (!out->open(tmp.string(), nz, specs.data())) throw std::runtime_error(file.string() + ": " + out->geterror());
    const std::size_t slice = static_cast<std::size_t>(l.size[0]) * static_cast<std::size_t>(l.size[1]);
    int z = 0;
    for (std::size_t k = 0; k < v.planes.size(); ++k) {
      const std::span<const float> slab = checked_slab(v, static_cast<int>(k));
      for (int p = 0; p < v.planes[k]; ++p, ++z) {
        if (z > 0 && !out->open(tmp.string(), specs[static_cast<std::size_t>(z)], ImageOutput::AppendSubimage))
          throw std::runtime_error(file.string() + ": " + out->geterror());
        if (!out->write_image(TypeDesc::FLOAT, slab.data() + static_cast<std::size_t>(p) * slice))
          throw std::runtime_error(file.string() + ": " + out->geterror());
      }
    }
    out->close();
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

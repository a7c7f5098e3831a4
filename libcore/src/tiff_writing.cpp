#include "tiff_writing.hpp"

#include <algorithm>
#include <memory>
#include <stdexcept>

#include "ctk/core/atomic_write.hpp"

namespace ctk {

namespace fs = std::filesystem;

void write_tiff_page(TIFF* t, const TiffPage& page, const fs::path& file) {
  const bool floats = page.samples == TiffPage::Samples::float32;
  const std::size_t bytes_per_sample = floats ? 4 : 2;
  // Strips of about 256 KiB: small enough to decode one row band at a time, large enough to compress.
  const auto rows_per_strip =
      std::max<std::uint32_t>(1, static_cast<std::uint32_t>(262144 / (bytes_per_sample * std::max<std::size_t>(1, page.cols))));
  TIFFSetField(t, TIFFTAG_IMAGEWIDTH, page.cols);
  TIFFSetField(t, TIFFTAG_IMAGELENGTH, page.rows);
  TIFFSetField(t, TIFFTAG_BITSPERSAMPLE, floats ? 32 : 16);
  TIFFSetField(t, TIFFTAG_SAMPLEFORMAT, floats ? SAMPLEFORMAT_IEEEFP : SAMPLEFORMAT_UINT);
  TIFFSetField(t, TIFFTAG_SAMPLESPERPIXEL, 1);
  TIFFSetField(t, TIFFTAG_PHOTOMETRIC, PHOTOMETRIC_MINISBLACK);
  TIFFSetField(t, TIFFTAG_PLANARCONFIG, PLANARCONFIG_CONTIG);
  TIFFSetField(t, TIFFTAG_COMPRESSION, COMPRESSION_ADOBE_DEFLATE);
  TIFFSetField(t, TIFFTAG_PREDICTOR, floats ? PREDICTOR_NONE : PREDICTOR_HORIZONTAL);
  TIFFSetField(t, TIFFTAG_ROWSPERSTRIP, rows_per_strip);
  if (page.pixels_per_unit) {
    TIFFSetField(t, TIFFTAG_XRESOLUTION, static_cast<float>(page.pixels_per_unit->first));
    TIFFSetField(t, TIFFTAG_YRESOLUTION, static_cast<float>(page.pixels_per_unit->second));
    TIFFSetField(t, TIFFTAG_RESOLUTIONUNIT, RESUNIT_NONE);
  }
  if (page.page_of) {
    TIFFSetField(t, TIFFTAG_SUBFILETYPE, FILETYPE_PAGE);
    TIFFSetField(t, TIFFTAG_PAGENUMBER, static_cast<std::uint16_t>(std::min(page.page_of->first, 65535)),
                 static_cast<std::uint16_t>(std::min(page.page_of->second, 65535)));
  }
  if (!page.description.empty()) TIFFSetField(t, TIFFTAG_IMAGEDESCRIPTION, page.description.c_str());
  const std::string which = page.page_of ? "page " + std::to_string(page.page_of->first) : std::string("the image");
  // libtiff takes a non-const buffer but, writing in the machine's byte order, leaves it as it was:
  // the predictor works on a copy of its own (libtiff 4.5: a uint16 image with the horizontal
  // predictor, compared before and after TIFFWriteEncodedStrip).
  auto* bytes = static_cast<unsigned char*>(const_cast<void*>(page.pixels));
  const std::size_t row_bytes = std::size_t{page.cols} * bytes_per_sample;
  for (std::uint32_t row = 0; row < page.rows; row += rows_per_strip) {
    const std::uint32_t count = std::min(rows_per_strip, page.rows - row);
    if (TIFFWriteEncodedStrip(t, TIFFComputeStrip(t, row, 0), bytes + std::size_t{row} * row_bytes,
                              static_cast<tmsize_t>(std::size_t{count} * row_bytes)) < 0)
      throw std::runtime_error(file.string() + ": cannot write " + which + " (disk full?)");
  }
  if (!TIFFWriteDirectory(t)) throw std::runtime_error(file.string() + ": cannot write " + which + " (disk full?)");
}

void write_tiff_atomically(const fs::path& file, const std::function<void(TIFF*)>& write_pages) {
  write_path_atomically(file, [&](const fs::path& tmp) {
    const std::unique_ptr<TIFF, void (*)(TIFF*)> out(TIFFOpen(tmp.c_str(), "w"), TIFFClose);
    if (!out) throw std::runtime_error(file.string() + ": cannot open for writing");
    write_pages(out.get());
  });
}

}  // namespace ctk

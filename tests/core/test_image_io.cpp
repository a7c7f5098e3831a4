// Image and volume files: round trips, integer counts kept as counts, real TIFFs from the
// measured data, and clear errors for missing, truncated or wrongly sized images.
#include "ctk/core/image_io.hpp"
#include "ctk/core/slice_preview.hpp"
#include "ctk/core/volume_file.hpp"

#include <gtest/gtest.h>

#include <OpenImageIO/imageio.h>

#include <sys/stat.h>

#include <cstdint>
#include <cstring>
#include <fstream>

#include "../test_support.hpp"
#include "ctk/core/error.hpp"

namespace ctk {
namespace {

Image ramp(int cols, int rows) {
  Image im{cols, rows, std::vector<float>(static_cast<std::size_t>(cols * rows))};
  for (std::size_t i = 0; i < im.pixels.size(); ++i) im.pixels[i] = 0.25f * static_cast<float>(i) - 3.0f;
  return im;
}

TEST(ImageIo, FloatTiffAndExrRoundTrip) {
  const auto dir = testing::scratch_dir();
  const Image im = ramp(13, 7);
  for (const char* name : {"a.tif", "a.exr"}) {
    write_image_float(im, dir / name);
    const Image back = read_image(dir / name, 13, 7);
    EXPECT_EQ(back.pixels, im.pixels) << name;
  }
}

TEST(ImageIo, Uint16CountsStayCounts) {
  const auto dir = testing::scratch_dir();
  std::vector<std::uint16_t> counts{0, 1, 1000, 65535, 40000, 7};
  auto out = OIIO::ImageOutput::create((dir / "c.tif").string());
  ASSERT_TRUE(out->open((dir / "c.tif").string(), OIIO::ImageSpec(3, 2, 1, OIIO::TypeDesc::UINT16)));
  ASSERT_TRUE(out->write_image(OIIO::TypeDesc::UINT16, counts.data()));
  out->close();
  const Image im = read_image(dir / "c.tif");
  for (std::size_t i = 0; i < counts.size(); ++i) EXPECT_EQ(im.pixels[i], counts[i]);
}

// Strip TIFFs of one channel go through libtiff directly, the rest through OpenImageIO: every
// sample type, compression, predictor, strip height (a last strip shorter than the rest), tiles
// and colour must give the values OpenImageIO reads (integer counts kept as counts).
TEST(ImageIo, EveryTiffLayoutReadsAsOpenImageIoReadsIt) {
  const auto dir = testing::scratch_dir();
  const int cols = 37, rows = 11;
  struct Layout {
    OIIO::TypeDesc type;
    int channels;
    const char* compression;
    int rows_per_strip;  // 0: tiles of 16 x 16
    double scale;        // counts per unit of OpenImageIO's float
  };
  const Layout layouts[] = {{OIIO::TypeDesc::UINT16, 1, "none", 11, 65535.0},     {OIIO::TypeDesc::UINT16, 1, "zip", 3, 65535.0},
                            {OIIO::TypeDesc::UINT16, 1, "lzw", 4, 65535.0},       {OIIO::TypeDesc::UINT8, 1, "zip", 5, 255.0},
                            {OIIO::TypeDesc::UINT32, 1, "none", 2, 4294967295.0}, {OIIO::TypeDesc::FLOAT, 1, "zip", 3, 1.0},
                            {OIIO::TypeDesc::UINT16, 1, "zip", 0, 65535.0},       {OIIO::TypeDesc::UINT16, 3, "zip", 4, 65535.0}};
  int n = 0;
  for (const Layout& l : layouts) {
    const auto file = dir / ("layout-" + std::to_string(n++) + ".tif");
    OIIO::ImageSpec spec(cols, rows, l.channels, l.type);
    spec.attribute("compression", l.compression);
    if (l.rows_per_strip > 0)
      spec.attribute("tiff:RowsPerStrip", l.rows_per_strip);
    else
      spec.tile_width = spec.tile_height = 16;
    std::vector<float> written(static_cast<std::size_t>(cols * rows * l.channels));
    for (std::size_t i = 0; i < written.size(); ++i) written[i] = static_cast<float>((i * 7919) % 1000) / 1000.0f;
    auto out = OIIO::ImageOutput::create(file.string());
    ASSERT_TRUE(out->open(file.string(), spec)) << out->geterror();
    ASSERT_TRUE(out->write_image(OIIO::TypeDesc::FLOAT, written.data())) << out->geterror();
    out->close();
    auto in = OIIO::ImageInput::open(file.string());
    ASSERT_TRUE(in);
    std::vector<float> expected(static_cast<std::size_t>(cols * rows));
    ASSERT_TRUE(in->read_image(0, 0, 0, 1, OIIO::TypeDesc::FLOAT, expected.data()));
    const Image im = read_image(file, cols, rows);
    ASSERT_EQ(im.pixels.size(), expected.size());
    for (std::size_t i = 0; i < expected.size(); ++i) {
      const float counts = l.scale == 1.0 ? expected[i] : static_cast<float>(std::round(expected[i] * l.scale));
      ASSERT_EQ(im.pixels[i], counts) << file << " pixel " << i;
    }
  }
}

TEST(ImageIo, ReadsTheMeasuredPepperFlatAndDark) {
  const auto dir = testing::shared_data_dir() / "flexray-pepper-cone";
  // The README: 190 rows x 239 columns, dark ~1 320, flat ~46 900 counts.
  const Image dark = read_image(dir / "di000000.tif", 239, 190), flat = read_image(dir / "io000000.tif", 239, 190);
  double d = 0, f = 0;
  for (float p : dark.pixels) d += p;
  for (float p : flat.pixels) f += p;
  d /= static_cast<double>(dark.pixels.size());
  f /= static_cast<double>(flat.pixels.size());
  EXPECT_NEAR(d, 1320, 200);
  EXPECT_NEAR(f, 46900, 3000);
}

TEST(ImageIo, BadImagesAreClearErrors) {
  const auto dir = testing::scratch_dir();
  EXPECT_THROW(read_image(dir / "missing.tif"), InputError);
  write_image_float(ramp(64, 64), dir / "full.tif");
  const auto size = std::filesystem::file_size(dir / "full.tif");
  std::filesystem::copy_file(dir / "full.tif", dir / "cut.tif");
  std::filesystem::resize_file(dir / "cut.tif", size / 2);
  EXPECT_THROW(read_image(dir / "cut.tif"), InputError);
  try {
    read_image(dir / "full.tif", 64, 63);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("full.tif"), std::string::npos);
    EXPECT_NE(std::string(e.what()).find("64 x 63"), std::string::npos) << e.what();
  }
}

// A 200-byte TIFF whose header claims 20000 x 20000 16-bit pixels.
void write_lying_tiff(const std::filesystem::path& file) {
  std::vector<unsigned char> bytes{'I', 'I', 42, 0, 8, 0, 0, 0};
  auto put = [&](std::uint32_t value, int size) {
    for (int i = 0; i < size; ++i) bytes.push_back(static_cast<unsigned char>(value >> (8 * i)));
  };
  const std::uint32_t entries[][3] = {{256, 4, 20000}, {257, 4, 20000}, {258, 3, 16},    {259, 3, 1},         {262, 3, 1},
                                      {273, 4, 200},   {277, 3, 1},     {278, 4, 20000}, {279, 4, 800000000u}};
  put(9, 2);
  for (const auto& e : entries) {
    put(e[0], 2);
    put(e[1], 2);
    put(1, 4);
    put(e[2], 4);
  }
  put(0, 4);
  bytes.resize(200, 0);
  std::ofstream(file, std::ios::binary)
      .write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
}

// A header is checked against the declared detector before any pixel memory is taken, and only
// regular files are read (a pipe would wait for a writer forever).
TEST(ImageIo, HeadersAreCheckedBeforeAllocationAndOnlyFilesAreRead) {
  const auto dir = testing::scratch_dir();
  write_lying_tiff(dir / "liar.tif");
  try {
    read_image(dir / "liar.tif", 64, 64);
    FAIL() << "a header of the wrong size was read";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("20000 x 20000"), std::string::npos) << e.what();
  }
  ASSERT_EQ(::mkfifo((dir / "pipe.tif").c_str(), 0600), 0);
  try {
    read_image(dir / "pipe.tif", 64, 64);
    FAIL() << "a pipe was opened";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("not a regular file"), std::string::npos) << e.what();
  }
  EXPECT_THROW(read_image(dir), InputError);
}

TEST(ImageIo, VolumeOutputs) {
  const auto dir = testing::scratch_dir();
  Volume v(VolumeLayout::centred({5, 4, 3}, {0.5, 0.5, 0.75}));
  for (std::size_t i = 0; i < v.data.size(); ++i) v.data[i] = static_cast<float>(i);
  write_volume(v, dir / "vol.nrrd");
  EXPECT_FALSE(std::filesystem::exists(dir / "vol.raw"));  // one file: header and data
  std::ifstream file(dir / "vol.nrrd", std::ios::binary);
  const std::string text((std::istreambuf_iterator<char>(file)), {});
  const std::size_t data = text.find("\n\n") + 2;
  ASSERT_EQ(text.size() - data, 60u * sizeof(float));
  const std::string header = text.substr(0, data);
  EXPECT_NE(header.find("sizes: 5 4 3"), std::string::npos);
  EXPECT_NE(header.find("space origin: (-1,-0.75,-0.75)"), std::string::npos) << header;
  EXPECT_EQ(header.find("data file"), std::string::npos);
  float last = 0;
  std::memcpy(&last, text.data() + text.size() - sizeof(float), sizeof(float));
  EXPECT_EQ(last, 59.0f);

  write_volume(v, dir / "vol.tif");
  auto in = OIIO::ImageInput::open((dir / "vol.tif").string());
  ASSERT_TRUE(in);
  int pages = 0;
  std::vector<float> page(20);
  while (in->seek_subimage(pages, 0)) {
    ASSERT_TRUE(in->read_image(pages, 0, 0, 1, OIIO::TypeDesc::FLOAT, page.data()));
    EXPECT_EQ(page[0], static_cast<float>(20 * pages));
    ++pages;
  }
  EXPECT_EQ(pages, 3);

  write_slice_png(v, 2, 1, 0, 59, dir / "z1.png");
  const Image png = read_image(dir / "z1.png");
  EXPECT_EQ(png.cols, 5);
  EXPECT_EQ(png.rows, 4);
  EXPECT_EQ(png.pixels[0], std::round(255.0f * 20 / 59));
}

}  // namespace
}  // namespace ctk

namespace ctk {
namespace {

// A volume bright only near its top (high z) and its +x side: the coronal and sagittal pictures
// show z up, the axial one x to the right; the labelled preview keeps the same orientation.
TEST(ImageIo, SlicesShowTheTopAtTheTop) {
  const auto dir = testing::scratch_dir();
  Volume v(VolumeLayout::centred({20, 16, 12}, Eigen::Vector3d(0.5, 0.5, 0.5)));
  for (int k = 9; k < 12; ++k)
    for (int j = 0; j < 16; ++j)
      for (int i = 14; i < 20; ++i) v.at(i, j, k) = 0.9f;
  write_slice_png(v, 1, 8, 0.0f, 1.0f, dir / "coronal.png");
  const Image coronal = read_image(dir / "coronal.png");
  ASSERT_EQ(coronal.cols, 20);
  ASSERT_EQ(coronal.rows, 12);
  EXPECT_EQ(coronal.pixels[19], std::round(0.9f * 255));  // top row, right end: z = 11, x = 19
  EXPECT_EQ(coronal.pixels[11 * 20 + 19], 0.0f);          // bottom row: z = 0
  write_slice_png(v, 0, 16, 0.0f, 1.0f, dir / "sagittal.png");
  const Image sagittal = read_image(dir / "sagittal.png");
  EXPECT_EQ(sagittal.pixels[0], std::round(0.9f * 255));
  EXPECT_EQ(sagittal.pixels[11 * 16], 0.0f);

  write_slice_preview(v, 1, 8, 0.0f, 1.0f, "1/mm", dir / "preview.png");
  const Image preview = read_image(dir / "preview.png");  // first channel of the RGB picture
  // The bright block (grey 230; the margin is white) lies in the picture's upper third, to the
  // right; none in its middle third (the bottom third holds the grey bar, whose light end is as
  // light).
  double top = 0, middle = 0, bright_x = 0;
  for (int r = 0; r < preview.rows; ++r)
    for (int c = 0; c < preview.cols; ++c) {
      const float g = preview.pixels[static_cast<std::size_t>(r * preview.cols + c)];
      if (g < 225.0f || g > 235.0f) continue;
      if (r < preview.rows / 3) {
        top += 1;
        bright_x += c;
      } else if (r < 2 * preview.rows / 3) {
        middle += 1;
      }
    }
  EXPECT_GT(top, 1000);
  EXPECT_EQ(middle, 0);
  EXPECT_GT(bright_x / top, 0.55 * preview.cols);
}

}  // namespace
}  // namespace ctk

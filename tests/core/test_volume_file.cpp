#include "ctk/core/volume_file.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <fstream>
#include <limits>

#include "../test_support.hpp"
#include "ctk/core/error.hpp"

namespace ctk {
namespace {

namespace fs = std::filesystem;

// Voxels whose bits a careless writer or reader would change: negative, tiny, huge, an exact
// decimal that float cannot hold, and a non-uniform layout with an origin off the centre.
Volume awkward_volume() {
  VolumeLayout l;
  l.size = {7, 5, 3};
  l.voxel_mm = {0.1, 0.25, 1.0 / 3.0};
  l.origin_mm = {-12.345678901234567, 0.5, 1e-3};
  Volume v(l);
  for (std::size_t i = 0; i < v.data.size(); ++i) v.data[i] = static_cast<float>(std::sin(0.7 * static_cast<double>(i)) * 1e-3);
  v.data[0] = -0.0f;
  v.data[1] = std::numeric_limits<float>::denorm_min();
  v.data[2] = 3.4e38f;
  v.data[3] = 0.1f;
  return v;
}

void expect_bitwise_equal(const Volume& a, const Volume& b) {
  EXPECT_EQ(a.layout.size, b.layout.size);
  for (int k = 0; k < 3; ++k) {
    EXPECT_EQ(a.layout.voxel_mm[k], b.layout.voxel_mm[k]) << "axis " << k;
    EXPECT_EQ(a.layout.origin_mm[k], b.layout.origin_mm[k]) << "axis " << k;
  }
  ASSERT_EQ(a.data.size(), b.data.size());
  for (std::size_t i = 0; i < a.data.size(); ++i)
    if (std::memcmp(&a.data[i], &b.data[i], sizeof(float)) != 0) {
      ADD_FAILURE() << "voxel " << i << ": " << a.data[i] << " became " << b.data[i];
      break;
    }
}

TEST(VolumeFile, EveryFormatRoundTripsBitwise) {
  const fs::path dir = testing::scratch_dir();
  const Volume v = awkward_volume();
  for (const char* name : {"v.nrrd", "v.mha", "v.mhd", "v.tif", "v.tiff", "v.h5", "v.hdf5", "V.NRRD"}) {
    SCOPED_TRACE(name);
    write_volume(v, dir / name);
    expect_bitwise_equal(read_volume(dir / name), v);
  }
  // .mhd keeps its voxels in the .raw beside it; the others are one file.
  EXPECT_TRUE(fs::exists(dir / "v.raw"));
  EXPECT_FALSE(fs::exists(dir / "V.raw"));
}

// A volume handed over slab by slab (a run whose slabs are on other ranks) is the same file's
// voxels: every format, slabs of uneven thickness and an empty one; each slab asked for once, in
// order; planes that do not add up refused before anything is written.
TEST(VolumeFile, EveryFormatWritesAVolumeSlabBySlab) {
  const fs::path dir = testing::scratch_dir();
  const Volume v = awkward_volume();
  const std::size_t plane = static_cast<std::size_t>(v.layout.size[0]) * static_cast<std::size_t>(v.layout.size[1]);
  const std::vector<int> planes{2, 0, 1};
  for (const char* name : {"s.nrrd", "s.mha", "s.mhd", "s.tif", "s.h5"}) {
    SCOPED_TRACE(name);
    std::vector<int> asked;
    std::vector<float> copy;  // each slab from a buffer of its own, as received from a rank
    const VolumeSlabs slabs{
        v.layout, planes, [&](int k) {
          asked.push_back(k);
          std::size_t first = 0;
          for (int j = 0; j < k; ++j) first += static_cast<std::size_t>(planes[static_cast<std::size_t>(j)]);
          copy.assign(v.data.begin() + static_cast<std::ptrdiff_t>(first * plane),
                      v.data.begin() + static_cast<std::ptrdiff_t>((first + planes[static_cast<std::size_t>(k)]) * plane));
          return std::span<const float>(copy);
        }};
    write_volume(slabs, dir / name);
    EXPECT_EQ(asked, (std::vector<int>{0, 1, 2}));
    expect_bitwise_equal(read_volume(dir / name), v);
  }
  const VolumeSlabs short_of_planes{v.layout, {2}, [&](int) { return std::span<const float>(v.data.data(), 2 * plane); }};
  EXPECT_THROW(write_volume(short_of_planes, dir / "short.nrrd"), std::invalid_argument);
  EXPECT_FALSE(fs::exists(dir / "short.nrrd"));
}

TEST(VolumeFile, AnUnknownExtensionIsRefusedNamingTheOption) {
  try {
    volume_format("volume.vol", "--out");
    FAIL() << "accepted .vol";
  } catch (const InputError& e) {
    EXPECT_EQ(e.where(), "--out");
    EXPECT_NE(std::string(e.what()).find(".nrrd, .mha"), std::string::npos) << e.what();
  }
  EXPECT_THROW(volume_format("volume"), InputError);
  EXPECT_THROW(write_volume(awkward_volume(), testing::scratch_dir() / "v.png"), InputError);
}

TEST(VolumeFile, ReadsOtherToolsHeadersDetachedDataAndBigEndian) {
  const fs::path dir = testing::scratch_dir();
  // 2 x 2 x 1 voxels, big-endian float32 in a detached file, NRRD "spacings" and no origin.
  const float values[4] = {1.5f, -2.0f, 0.25f, 8.0f};
  {
    std::ofstream raw(dir / "be.raw", std::ios::binary);
    for (float f : values) {
      std::uint32_t u = 0;
      std::memcpy(&u, &f, 4);
      u = __builtin_bswap32(u);
      raw.write(reinterpret_cast<const char*>(&u), 4);
    }
  }
  std::ofstream(dir / "be.nrrd") << "NRRD0005\n# another tool\ntype: float\ndimension: 3\nsizes: 2 2 1\nspacings: 0.5 0.5 2\n"
                                    "endian: big\nencoding: raw\ndata file: be.raw\n\n";
  const Volume n = read_volume(dir / "be.nrrd");
  EXPECT_EQ(n.layout.size, (std::array<int, 3>{2, 2, 1}));
  EXPECT_EQ(n.layout.voxel_mm.z(), 2.0);
  EXPECT_EQ(n.layout.origin_mm.x(), -0.25);  // centred when the header gives no origin
  for (int i = 0; i < 4; ++i) EXPECT_EQ(n.data[static_cast<std::size_t>(i)], values[i]);
  std::ofstream(dir / "be.mhd") << "ObjectType = Image\nNDims = 3\nDimSize = 2 2 1\nElementSize = 0.5 0.5 2\n"
                                   "ElementByteOrderMSB = True\nElementType = MET_FLOAT\nElementDataFile = be.raw\n";
  const Volume m = read_volume(dir / "be.mhd");
  for (int i = 0; i < 4; ++i) EXPECT_EQ(m.data[static_cast<std::size_t>(i)], values[i]);
}

TEST(VolumeFile, DamagedFilesNameFileAndKey) {
  const fs::path dir = testing::scratch_dir();
  write_volume(awkward_volume(), dir / "v.mhd");
  fs::resize_file(dir / "v.raw", 100);  // truncated data
  try {
    read_volume(dir / "v.mhd");
    FAIL() << "read a truncated volume";
  } catch (const InputError& e) {
    EXPECT_EQ(e.file(), (dir / "v.raw").string());
    EXPECT_NE(std::string(e.what()).find("declares 420"), std::string::npos) << e.what();
  }
  std::ofstream(dir / "u8.nrrd") << "NRRD0004\ntype: uchar\ndimension: 3\nsizes: 1 1 1\nencoding: raw\n\nx";
  try {
    read_volume(dir / "u8.nrrd");
    FAIL() << "read uchar voxels";
  } catch (const InputError& e) {
    EXPECT_EQ(e.where(), "field 'type'");
  }
  // A header claiming a volume larger than memory costs nothing.
  std::ofstream(dir / "huge.mha")
      << "NDims = 3\nDimSize = 100000 100000 100000\nElementType = MET_FLOAT\nElementDataFile = LOCAL\n";
  EXPECT_THROW(read_volume(dir / "huge.mha"), InputError);
  std::ofstream(dir / "text.h5") << "not hdf5";
  EXPECT_THROW(read_volume(dir / "text.h5"), InputError);
  EXPECT_THROW(read_volume(dir / "missing.nrrd"), InputError);
}

}  // namespace
}  // namespace ctk

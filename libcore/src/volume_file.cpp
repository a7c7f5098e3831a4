#include "ctk/core/volume_file.hpp"

#include <algorithm>
#include <bit>
#include <cctype>
#include <cmath>
#include <cstring>
#include <fstream>
#include <sstream>

#include "ctk/core/error.hpp"
#include "volume_formats.hpp"

namespace ctk {

namespace volume_formats {

std::span<const float> checked_slab(const VolumeSlabs& v, int k) {
  const std::size_t plane = static_cast<std::size_t>(v.layout.size[0]) * static_cast<std::size_t>(v.layout.size[1]);
  const std::span<const float> slab = v.slab(k);
  if (slab.size() != plane * static_cast<std::size_t>(v.planes[static_cast<std::size_t>(k)]))
    throw std::invalid_argument("write_volume: slab " + std::to_string(k) + " has " + std::to_string(slab.size()) +
                                " voxels, not its planes'");
  return slab;
}

void write_raw_slabs(const VolumeSlabs& v, std::ostream& out) {
  for (std::size_t k = 0; k < v.planes.size(); ++k) {
    const std::span<const float> slab = checked_slab(v, static_cast<int>(k));
    out.write(reinterpret_cast<const char*>(slab.data()), static_cast<std::streamsize>(slab.size_bytes()));
  }
}

}  // namespace volume_formats

namespace fs = std::filesystem;

namespace {

std::string lower_extension(const fs::path& file) {
  std::string e = file.extension().string();
  std::transform(e.begin(), e.end(), e.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return e;
}

}  // namespace

VolumeFormat volume_format(const fs::path& file, const std::string& what) {
  const std::string e = lower_extension(file);
  if (e == ".nrrd") return VolumeFormat::nrrd;
  if (e == ".mha") return VolumeFormat::metaimage;
  if (e == ".mhd") return VolumeFormat::metaimage_detached;
  if (e == ".tif" || e == ".tiff") return VolumeFormat::tiff;
  if (e == ".h5" || e == ".hdf5") return VolumeFormat::hdf5;
  throw InputError(file.string(), what,
                   "a volume file's extension names its format: .nrrd, .mha, .mhd (+ .raw), .tif or .tiff, .h5 or .hdf5; got '" +
                       file.extension().string() + "'");
}

std::vector<fs::path> volume_files(const fs::path& file) {
  if (volume_format(file) == VolumeFormat::metaimage_detached) return {file, fs::path(file).replace_extension(".raw")};
  return {file};
}

void write_volume(const Volume& volume, const fs::path& file) {
  write_volume(VolumeSlabs{volume.layout,
                           {volume.layout.size[2]},
                           [&](int) { return std::span<const float>(volume.data.data(), volume.data.size()); }},
               file);
}

void write_volume(const VolumeSlabs& volume, const fs::path& file) {
  int planes = 0;
  for (int p : volume.planes) planes += p;
  if (planes != volume.layout.size[2] || std::any_of(volume.planes.begin(), volume.planes.end(), [](int p) { return p < 0; }))
    throw std::invalid_argument("write_volume: the slabs' planes do not add up to the volume's " +
                                std::to_string(volume.layout.size[2]));
  switch (volume_format(file)) {
    case VolumeFormat::nrrd:
      return volume_formats::write_nrrd(volume, file);
    case VolumeFormat::metaimage:
      return volume_formats::write_metaimage(volume, file, false);
    case VolumeFormat::metaimage_detached:
      return volume_formats::write_metaimage(volume, file, true);
    case VolumeFormat::tiff:
      return volume_formats::write_tiff(volume, file);
    case VolumeFormat::hdf5:
      return volume_formats::write_hdf5(volume, file);
  }
}

Volume read_volume(const fs::path& file) {
  const VolumeFormat format = volume_format(file);
  require_regular_file(file);
  switch (format) {
    case VolumeFormat::nrrd:
      return volume_formats::read_nrrd(file);
    case VolumeFormat::metaimage:
    case VolumeFormat::metaimage_detached:
      return volume_formats::read_metaimage(file);
    case VolumeFormat::tiff:
      return volume_formats::read_tiff(file);
    case VolumeFormat::hdf5:
      return volume_formats::read_hdf5(file);
  }
  return Volume{};
}

namespace volume_formats {

// 2^33 voxels (32 GiB of floats): a header claiming more is damaged or hostile.
constexpr double kMostVoxels = 8589934592.0;

void check_layout(const VolumeLayout& l, const fs::path& file, const std::string& key) {
  double voxels = 1;
  for (int s : l.size) {
    if (s <= 0) throw InputError(file.string(), key, "sizes must be positive, got " + std::to_string(s));
    voxels *= s;
  }
  if (voxels > kMostVoxels)
    throw InputError(file.string(), key, "claims " + std::to_string(voxels) + " voxels: more than any volume ctk reads");
  for (int a = 0; a < 3; ++a)
    if (!(std::isfinite(l.voxel_mm[a]) && l.voxel_mm[a] > 0) || !std::isfinite(l.origin_mm[a]))
      throw InputError(file.string(), key, "voxel sizes must be positive and the origin finite");
}

void read_raw_voxels(const fs::path& data_file, std::uintmax_t offset, bool big_endian, Volume& volume) {
  require_regular_file(data_file);
  const std::uintmax_t bytes = volume.layout.voxel_count() * sizeof(float);
  const std::uintmax_t size = fs::file_size(data_file);
  if (size < offset || size - offset != bytes)
    throw InputError(data_file.string(), "",
                     "holds " + std::to_string(size < offset ? 0 : size - offset) + " bytes of voxels, the header declares " +
                         std::to_string(bytes) + " (" + std::to_string(volume.layout.voxel_count()) + " float32 voxels)");
  std::ifstream in(data_file, std::ios::binary);
  in.seekg(static_cast<std::streamoff>(offset));
  in.read(reinterpret_cast<char*>(volume.data.data()), static_cast<std::streamsize>(bytes));
  if (!in) throw InputError(data_file.string(), "", "cannot read the voxels");
  if (big_endian != (std::endian::native == std::endian::big))
    for (float& f : volume.data) {
      std::uint32_t u = 0;
      std::memcpy(&u, &f, sizeof u);
      u = __builtin_bswap32(u);
      std::memcpy(&f, &u, sizeof u);
    }
}

std::vector<double> parse_numbers(const std::string& text, std::size_t count, const fs::path& file, const std::string& key) {
  std::string cleaned = text;
  for (char& c : cleaned)
    if (c == '(' || c == ')' || c == ',') c = ' ';
  std::istringstream in(cleaned);
  std::vector<double> values;
  std::string word;
  while (in >> word) {
    std::size_t used = 0;
    double value = 0;
    try {
      value = std::stod(word, &used);
    } catch (const std::exception&) {
      used = 0;
    }
    if (used != word.size() || !std::isfinite(value))
      throw InputError(file.string(), key, "expected " + std::to_string(count) + " numbers, got '" + text + "'");
    values.push_back(value);
  }
  if (values.size() != count)
    throw InputError(file.string(), key, "expected " + std::to_string(count) + " numbers, got '" + text + "'");
  return values;
}

Eigen::Vector3d parse_vector3(const std::string& text, const fs::path& file, const std::string& key) {
  const auto v = parse_numbers(text, 3, file, key);
  return {v[0], v[1], v[2]};
}

}  // namespace volume_formats

}  // namespace ctk

#pragma once
// The volume formats behind volume_file.hpp, one file each, and what their readers share.
#include <cstdint>
#include <filesystem>
#include <ostream>
#include <string>
#include <vector>

#include "ctk/core/volume.hpp"
#include "ctk/core/volume_file.hpp"

namespace ctk::volume_formats {

void write_nrrd(const VolumeSlabs& volume, const std::filesystem::path& file);
Volume read_nrrd(const std::filesystem::path& file);

/// `detached`: the header in `file`, the voxels in `file` with extension .raw.
void write_metaimage(const VolumeSlabs& volume, const std::filesystem::path& file, bool detached);
Volume read_metaimage(const std::filesystem::path& file);

void write_tiff(const VolumeSlabs& volume, const std::filesystem::path& file);
Volume read_tiff(const std::filesystem::path& file);

void write_hdf5(const VolumeSlabs& volume, const std::filesystem::path& file);

/// Slab k's voxels, checked to be its planes' (std::invalid_argument otherwise).
std::span<const float> checked_slab(const VolumeSlabs& volume, int k);

/// Every slab's voxels written to `out` in order (the raw data of NRRD and MetaImage).
void write_raw_slabs(const VolumeSlabs& volume, std::ostream& out);
Volume read_hdf5(const std::filesystem::path& file);

/// A layout read from a header: sizes positive and their product within reason, spacings positive
/// and finite (InputError naming `file` and `key` otherwise).
void check_layout(const VolumeLayout& layout, const std::filesystem::path& file, const std::string& key);

/// The voxels stored raw in `data_file` from byte `offset` on, float32 in the given byte order; the
/// file must hold exactly that many bytes after the offset (InputError naming it otherwise).
void read_raw_voxels(const std::filesystem::path& data_file, std::uintmax_t offset, bool big_endian, Volume& volume);

/// "(1.5,0,0)" or "1.5 2 3" style lists of numbers; InputError naming `file` and `key` unless
/// there are `count` of them.
std::vector<double> parse_numbers(const std::string& text, std::size_t count, const std::filesystem::path& file,
                                  const std::string& key);

/// Three numbers (x, y, z) as parse_numbers reads them.
Eigen::Vector3d parse_vector3(const std::string& text, const std::filesystem::path& file, const std::string& key);

}  // namespace ctk::volume_formats

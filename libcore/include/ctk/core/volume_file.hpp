#pragma once
// Volumes in and out, the format named by the file's extension:
//   .nrrd        NRRD, header and data in one file (3D Slicer, ITK, ParaView)
//   .mha         MetaImage, header and data in one file (ITK, RTK, elastix)
//   .mhd         MetaImage header, the data in a .raw file of the same name beside it
//   .tif, .tiff  one float32 page per z slice, ImageJ's description with the spacing (Fiji)
//   .h5, .hdf5   HDF5: dataset "volume" of float32 indexed [z][y][x] (numpy, h5py, CIL order),
//                attributes "voxel_mm" and "origin_mm" as (x, y, z)
// Every format keeps the float32 voxels bitwise, the voxel size and the origin (the centre of
// voxel 0, holder frame, mm). Outputs are written atomically.
#include <filesystem>
#include <functional>
#include <span>
#include <string>
#include <vector>

#include "ctk/core/volume.hpp"

namespace ctk {

enum class VolumeFormat { nrrd, metaimage, metaimage_detached, tiff, hdf5 };

/// The format `file`'s extension names. An unknown extension is an InputError naming `what` (the
/// option or key that gave the path) and the extensions there are, so it is refused before any work.
VolumeFormat volume_format(const std::filesystem::path& file, const std::string& what = "volume file");

/// The files writing a volume to `file` creates: `file`, and for .mhd the .raw beside it.
std::vector<std::filesystem::path> volume_files(const std::filesystem::path& file);

/// Writes `volume` in the format of `file`'s extension (InputError for an unknown one).
void write_volume(const Volume& volume, const std::filesystem::path& file);

/// A volume handed to a writer in slabs of z planes, in order, so that the writer never holds it
/// whole (a run whose slabs are on other ranks): `planes[k]` planes in slab k (summing to the
/// layout's), `slab(k)` their voxels (x fastest), valid until the next call; called once per
/// slab, in order.
struct VolumeSlabs {
  VolumeLayout layout;
  std::vector<int> planes;
  std::function<std::span<const float>(int slab)> slab;
};

/// The same, slab by slab; std::invalid_argument when the planes do not add up to the layout's.
void write_volume(const VolumeSlabs& volume, const std::filesystem::path& file);

/// Reads a volume any of the writers wrote (and such files from other tools: NRRD and MetaImage
/// with float voxels and axis-aligned spacing, raw encoding, either byte order). InputError naming
/// the file and the key when it cannot.
Volume read_volume(const std::filesystem::path& file);

}  // namespace ctk

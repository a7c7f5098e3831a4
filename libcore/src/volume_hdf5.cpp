// A volume as HDF5 (HDF Group's C library): dataset "volume", float32, dimensions (z, y, x) so
// that numpy and h5py see volume[z, y, x] as ctk stores it; attributes "voxel_mm" and
// "origin_mm" (x, y, z) on the dataset.
#include <hdf5.h>

#include <array>
#include <optional>
#include <utility>

#include "ctk/core/atomic_write.hpp"
#include "ctk/core/error.hpp"
#include "hdf5_handle.hpp"
#include "volume_formats.hpp"

namespace ctk::volume_formats {

namespace fs = std::filesystem;

using hdf5::Handle;
using hdf5::quiet_library;

namespace {

void write_vector_attribute(hid_t dataset, const char* name, const Eigen::Vector3d& value) {
  const hsize_t three = 3;
  const Handle space(H5Screate_simple(1, &three, nullptr), H5Sclose);
  const Handle attribute(H5Acreate2(dataset, name, H5T_IEEE_F64LE, space.get(), H5P_DEFAULT, H5P_DEFAULT), H5Aclose);
  const std::array<double, 3> v{value.x(), value.y(), value.z()};
  if (!attribute.valid() || H5Awrite(attribute.get(), H5T_NATIVE_DOUBLE, v.data()) < 0)
    throw std::runtime_error(std::string("HDF5: cannot write attribute ") + name);
}

// An attribute of three numbers, or nothing when it is absent.
std::optional<Eigen::Vector3d> read_vector_attribute(hid_t dataset, const char* name, const fs::path& file) {
  if (H5Aexists(dataset, name) <= 0) return std::nullopt;
  const Handle attribute(H5Aopen(dataset, name, H5P_DEFAULT), H5Aclose);
  const Handle space(H5Aget_space(attribute.get()), H5Sclose);
  if (!attribute.valid() || H5Sget_simple_extent_npoints(space.get()) != 3)
    throw InputError(file.string(), std::string("attribute '") + name + "'", "expected three numbers (x, y, z)");
  std::array<double, 3> v{};
  if (H5Aread(attribute.get(), H5T_NATIVE_DOUBLE, v.data()) < 0)
    throw InputError(file.string(), std::string("attribute '") + name + "'", "expected three numbers (x, y, z)");
  return Eigen::Vector3d(v[0], v[1], v[2]);
}

}  // namespace

void write_hdf5(const VolumeSlabs& v, const fs::path& file) {
  quiet_library();
  write_path_atomically(file, [&](const fs::path& tmp) {
    const Handle h5(H5Fcreate(tmp.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT), H5Fclose);
    if (!h5.valid()) throw std::runtime_error(file.string() + ": cannot create the HDF5 file");
    const std::array<hsize_t, 3> dims{static_cast<hsize_t>(v.layout.size[2]), static_cast<hsize_t>(v.layout.size[1]),
                                      static_cast<hsize_t>(v.layout.size[0])};
    const Handle space(H5Screate_simple(3, dims.data(), nullptr), H5Sclose);
    const Handle dataset(H5Dcreate2(h5.get(), "volume", H5T_IEEE_F32LE, space.get(), H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT),
                         H5Dclose);
    if (!dataset.valid()) throw std::runtime_error(file.string() + ": cannot write the dataset 'volume'");
    hsize_t z = 0;
    for (std::size_t k = 0; k < v.planes.size(); ++k) {
      const std::span<const float> slab = checked_slab(v, static_cast<int>(k));
      const std::array<hsize_t, 3> start{z, 0, 0}, count{static_cast<hsize_t>(v.planes[k]), dims[1], dims[2]};
      z += count[0];
      if (count[0] == 0) continue;
      const Handle memory(H5Screate_simple(3, count.data(), nullptr), H5Sclose);
      if (H5Sselect_hyperslab(space.get(), H5S_SELECT_SET, start.data(), nullptr, count.data(), nullptr) < 0 ||
          H5Dwrite(dataset.get(), H5T_NATIVE_FLOAT, memory.get(), space.get(), H5P_DEFAULT, slab.data()) < 0)
        throw std::runtime_error(file.string() + ": cannot write the dataset 'volume'");
    }
    write_vector_attribute(dataset.get(), "voxel_mm", v.layout.voxel_mm);
    write_vector_attribute(dataset.get(), "origin_mm", v.layout.origin_mm);
  });
}

Volume read_hdf5(const fs::path& file) {
  quiet_library();
  if (H5Fis_hdf5(file.c_str()) <= 0) throw InputError(file.string(), "", "not an HDF5 file");
  const Handle h5(H5Fopen(file.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT), H5Fclose);
  if (!h5.valid()) throw InputError(file.string(), "", "cannot open the HDF5 file");
  if (H5Lexists(h5.get(), "volume", H5P_DEFAULT) <= 0) throw InputError(file.string(), "dataset 'volume'", "missing");
  const Handle dataset(H5Dopen2(h5.get(), "volume", H5P_DEFAULT), H5Dclose);
  const Handle space(H5Dget_space(dataset.get()), H5Sclose);
  const Handle type(H5Dget_type(dataset.get()), H5Tclose);
  if (!dataset.valid() || !space.valid() || H5Sget_simple_extent_ndims(space.get()) != 3)
    throw InputError(file.string(), "dataset 'volume'", "expected three dimensions (z, y, x)");
  if (H5Tget_class(type.get()) != H5T_FLOAT)
    throw InputError(file.string(), "dataset 'volume'", "expected floating-point voxels");
  std::array<hsize_t, 3> dims{};
  H5Sget_simple_extent_dims(space.get(), dims.data(), nullptr);
  VolumeLayout l;
  for (int a = 0; a < 3; ++a) {
    const hsize_t d = dims[static_cast<std::size_t>(2 - a)];
    l.size[static_cast<std::size_t>(a)] = d > (1u << 30) ? -1 : static_cast<int>(d);
  }
  l.voxel_mm = read_vector_attribute(dataset.get(), "voxel_mm", file).value_or(Eigen::Vector3d(1, 1, 1));
  const auto origin = read_vector_attribute(dataset.get(), "origin_mm", file);
  l.origin_mm = origin ? *origin : VolumeLayout::centred(l.size, l.voxel_mm).origin_mm;
  check_layout(l, file, "dataset 'volume'");
  Volume v(l);
  if (H5Dread(dataset.get(), H5T_NATIVE_FLOAT, H5S_ALL, H5S_ALL, H5P_DEFAULT, v.data.data()) < 0)
    throw InputError(file.string(), "dataset 'volume'", "cannot read the voxels");
  return v;
}

}  // namespace ctk::volume_formats

#pragma once
// Small writers of other tools' scan files, from the facts of their formats (NeXus NXtomo; Nikon's
// .xtekct), with projections of two balls computed ray by ray in each format's own lab frame, so
// that an importer's matrices and images can be checked against a geometry it did not derive.
#include <hdf5.h>

#include <Eigen/Geometry>
#include <array>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <functional>
#include <stdexcept>
#include <string>
#include <vector>

#include "ctk/core/image_io.hpp"

namespace ctk::testing {

struct Ball {
  Eigen::Vector3d centre_mm;  // in the sample frame ctk reconstructs (axis along +z)
  double radius_mm;
  double attenuation_per_mm;
};

inline std::vector<Ball> two_balls() { return {{{6, -4, 5}, 3.0, 0.05}, {{-7, 3, -6}, 2.0, 0.08}}; }

/// Line integral through the balls along the ray from `source` towards `pixel` (lab frame), the
/// balls placed in the lab by `to_lab`.
inline double ball_line_integral(const Eigen::Vector3d& source, const Eigen::Vector3d& pixel, const std::vector<Ball>& balls,
                                 const std::function<Eigen::Vector3d(const Eigen::Vector3d&)>& to_lab) {
  const Eigen::Vector3d d = (pixel - source).normalized();
  double sum = 0;
  for (const Ball& b : balls) {
    const Eigen::Vector3d c = to_lab(b.centre_mm) - source;
    const double along = c.dot(d), miss2 = c.squaredNorm() - along * along;
    if (miss2 < b.radius_mm * b.radius_mm) sum += 2.0 * std::sqrt(b.radius_mm * b.radius_mm - miss2) * b.attenuation_per_mm;
  }
  return sum;
}

struct ConeSetup {
  int cols = 96, rows = 80;
  double pitch_mm = 0.8;
  double source_to_axis_mm = 200, source_to_detector_mm = 400;
  int views = 90;
  double open_counts = 20000, dark_counts = 100;
};

// --- NeXus NXtomo: McStas lab frame (z along the beam, y up, x completing a right-handed frame);
// the source upstream at z = -SOD, the axis through the origin along +y, the detector at
// z = SDD - SOD with columns along +x and row 0 at the top; the sample turns right-handed about +y.
// ctk's sample frame (axis +z, source at +y at angle 0) maps to McStas' by (x, y, z) -> (x, z, -y).

inline Eigen::Vector3d ctk_to_mcstas(const Eigen::Vector3d& p) { return {p.x(), p.z(), -p.y()}; }

inline Eigen::Vector2d mcstas_projection(const ConeSetup& s, double angle_rad, const Eigen::Vector3d& sample_point) {
  const Eigen::Vector3d lab = Eigen::AngleAxisd(angle_rad, Eigen::Vector3d::UnitY()) * ctk_to_mcstas(sample_point);
  const Eigen::Vector3d source(0, 0, -s.source_to_axis_mm);
  const double plane = s.source_to_detector_mm - s.source_to_axis_mm;
  const Eigen::Vector3d hit = source + (lab - source) * ((plane - source.z()) / (lab.z() - source.z()));
  return {hit.x() / s.pitch_mm + 0.5 * (s.cols - 1), 0.5 * (s.rows - 1) - hit.y() / s.pitch_mm};
}

inline std::vector<float> mcstas_frame(const ConeSetup& s, double angle_rad, const std::vector<Ball>& balls) {
  std::vector<float> counts(static_cast<std::size_t>(s.cols) * static_cast<std::size_t>(s.rows));
  const Eigen::Vector3d source(0, 0, -s.source_to_axis_mm);
  const auto to_lab = [&](const Eigen::Vector3d& p) {
    return Eigen::Vector3d(Eigen::AngleAxisd(angle_rad, Eigen::Vector3d::UnitY()) * ctk_to_mcstas(p));
  };
  for (int j = 0; j < s.rows; ++j)
    for (int i = 0; i < s.cols; ++i) {
      const Eigen::Vector3d pixel((i - 0.5 * (s.cols - 1)) * s.pitch_mm, (0.5 * (s.rows - 1) - j) * s.pitch_mm,
                                  s.source_to_detector_mm - s.source_to_axis_mm);
      counts[static_cast<std::size_t>(j * s.cols + i)] = static_cast<float>(
          std::round(s.dark_counts + s.open_counts * std::exp(-ball_line_integral(source, pixel, balls, to_lab))));
    }
  return counts;
}

namespace nexus_writing {

inline void check(herr_t status, const char* what) {
  if (status < 0) throw std::runtime_error(std::string("HDF5 test writer: ") + what);
}

inline void string_attribute(hid_t object, const char* name, const std::string& value) {
  const hid_t type = H5Tcopy(H5T_C_S1);
  H5Tset_size(type, value.size());
  const hid_t space = H5Screate(H5S_SCALAR);
  const hid_t a = H5Acreate2(object, name, type, space, H5P_DEFAULT, H5P_DEFAULT);
  check(H5Awrite(a, type, value.data()), name);
  H5Aclose(a);
  H5Sclose(space);
  H5Tclose(type);
}

inline hid_t group(hid_t parent, const char* name, const char* nx_class) {
  const hid_t g = H5Gcreate2(parent, name, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
  string_attribute(g, "NX_class", nx_class);
  return g;
}

inline void string_dataset(hid_t parent, const char* name, const std::string& value) {
  const hid_t type = H5Tcopy(H5T_C_S1);
  H5Tset_size(type, value.size());
  const hid_t space = H5Screate(H5S_SCALAR);
  const hid_t d = H5Dcreate2(parent, name, type, space, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
  check(H5Dwrite(d, type, H5S_ALL, H5S_ALL, H5P_DEFAULT, value.data()), name);
  H5Dclose(d);
  H5Sclose(space);
  H5Tclose(type);
}

template <typename T>
void numbers(hid_t parent, const char* name, hid_t file_type, hid_t memory_type, const std::vector<T>& values,
             const std::string& units = {}) {
  const hsize_t n = values.size();
  const hid_t space = values.size() == 1 ? H5Screate(H5S_SCALAR) : H5Screate_simple(1, &n, nullptr);
  const hid_t d = H5Dcreate2(parent, name, file_type, space, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
  check(H5Dwrite(d, memory_type, H5S_ALL, H5S_ALL, H5P_DEFAULT, values.data()), name);
  if (!units.empty()) string_attribute(d, "units", units);
  H5Dclose(d);
  H5Sclose(space);
}

}  // namespace nexus_writing

/// What goes into the test's NXtomo file.
struct NxTomoContent {
  ConeSetup setup;
  std::vector<int> keys;           // per frame: 0 projection, 1 flat, 2 dark, 3 invalid
  std::vector<double> angles_deg;  // per frame
  std::vector<std::vector<float>> frames;
  bool write_distances = true;  // source and detector distances, pixel sizes (in m and um)
  bool write_angles = true;
  int data_rank = 3;
};

/// Frames in file order: 2 darks, 2 flats, the projections with an invalid frame among them, a flat.
inline NxTomoContent nxtomo_scan(const ConeSetup& s, const std::vector<Ball>& balls) {
  NxTomoContent c;
  c.setup = s;
  const std::vector<float> dark(static_cast<std::size_t>(s.cols * s.rows), static_cast<float>(s.dark_counts));
  const std::vector<float> flat(static_cast<std::size_t>(s.cols * s.rows), static_cast<float>(s.dark_counts + s.open_counts));
  auto add = [&](int key, double angle, const std::vector<float>& frame) {
    c.keys.push_back(key);
    c.angles_deg.push_back(angle);
    c.frames.push_back(frame);
  };
  add(2, 0, dark);
  add(2, 0, dark);
  add(1, 0, flat);
  add(1, 0, flat);
  for (int k = 0; k < s.views; ++k) {
    const double angle = 360.0 * k / s.views;
    add(0, angle, mcstas_frame(s, angle * M_PI / 180.0, balls));
    if (k == s.views / 2) add(3, angle, dark);  // a frame the beamline marked invalid
  }
  add(1, 360, flat);
  return c;
}

/// Writes `/entry` (NXentry, definition NXtomo) as NXtomo lays it out, frames as uint16.
inline void write_nxtomo(const std::filesystem::path& file, const NxTomoContent& c) {
  using namespace nexus_writing;
  const hid_t h5 = H5Fcreate(file.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT);
  if (h5 < 0) throw std::runtime_error("cannot create " + file.string());
  const hid_t entry = group(h5, "entry", "NXentry");
  string_dataset(entry, "definition", "NXtomo");
  const hid_t instrument = group(entry, "instrument", "NXinstrument");
  const hid_t source = group(instrument, "xray_tube", "NXsource");
  const hid_t detector = group(instrument, "detector", "NXdetector");
  const hid_t sample = group(entry, "sample", "NXsample");
  const ConeSetup& s = c.setup;
  std::vector<std::uint16_t> pixels;
  for (const auto& f : c.frames)
    for (float p : f) pixels.push_back(static_cast<std::uint16_t>(p));
  const std::array<hsize_t, 3> dims{c.frames.size(), static_cast<hsize_t>(s.rows), static_cast<hsize_t>(s.cols)};
  const std::array<hsize_t, 2> flat_dims{c.frames.size(), static_cast<hsize_t>(s.rows) * static_cast<hsize_t>(s.cols)};
  const hid_t space =
      c.data_rank == 3 ? H5Screate_simple(3, dims.data(), nullptr) : H5Screate_simple(2, flat_dims.data(), nullptr);
  const hid_t data = H5Dcreate2(detector, "data", H5T_STD_U16LE, space, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
  check(H5Dwrite(data, H5T_NATIVE_UINT16, H5S_ALL, H5S_ALL, H5P_DEFAULT, pixels.data()), "data");
  H5Dclose(data);
  H5Sclose(space);
  numbers(detector, "image_key", H5T_STD_I32LE, H5T_NATIVE_INT, c.keys);
  if (c.write_angles) {
    std::vector<double> radians;
    for (double a : c.angles_deg) radians.push_back(a * M_PI / 180.0);
    numbers(sample, "rotation_angle", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, radians, "rad");
  }
  if (c.write_distances) {
    numbers(detector, "x_pixel_size", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, std::vector<double>{s.pitch_mm * 1e-3}, "m");
    numbers(detector, "y_pixel_size", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, std::vector<double>{s.pitch_mm * 1e3}, "um");
    numbers(detector, "distance", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE,
            std::vector<double>{(s.source_to_detector_mm - s.source_to_axis_mm) / 10}, "cm");
    numbers(source, "distance", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, std::vector<double>{-s.source_to_axis_mm}, "mm");
  }
  for (hid_t g : {sample, detector, source, instrument, entry}) H5Gclose(g);
  H5Fclose(h5);
}

// --- Nikon .xtekct, as CIL's reader documents it: the source at the origin, the beam along +y, z
// up; the axis at (-ObjectOffsetX, SrcToObject, 0), tilted about x by -ObjectTilt and rolled about y
// by ObjectRoll; the detector centred at (0, SrcToDetector, 0) with its first pixel at the top
// right seen from the source; view k at 180 - (InitialAngle + k AngularStep) deg, the sample turning
// right-handed about the axis. The sample frame: lab = axis point + axis frame Rz(angle) sample.

struct NikonContent {
  ConeSetup setup;
  double initial_angle_deg = 30, angular_step_deg = 4;
  double object_offset_x_mm = 1.5, object_tilt_deg = 0, object_roll_deg = 0;
  std::string name = "ball";
};

inline Eigen::Matrix3d nikon_sample_to_lab(const NikonContent& c, int view) {
  const double angle = (180.0 - (c.initial_angle_deg + view * c.angular_step_deg)) * M_PI / 180.0;
  return (Eigen::AngleAxisd(-c.object_tilt_deg * M_PI / 180.0, Eigen::Vector3d::UnitX()) *
          Eigen::AngleAxisd(c.object_roll_deg * M_PI / 180.0, Eigen::Vector3d::UnitY()) *
          Eigen::AngleAxisd(angle, Eigen::Vector3d::UnitZ()))
      .toRotationMatrix();
}

inline Eigen::Vector3d nikon_lab(const NikonContent& c, int view, const Eigen::Vector3d& sample_point) {
  return Eigen::Vector3d(-c.object_offset_x_mm, c.setup.source_to_axis_mm, 0) + nikon_sample_to_lab(c, view) * sample_point;
}

inline Eigen::Vector2d nikon_projection(const NikonContent& c, int view, const Eigen::Vector3d& sample_point) {
  const ConeSetup& s = c.setup;
  const Eigen::Vector3d lab = nikon_lab(c, view, sample_point);
  const Eigen::Vector3d hit = lab * (s.source_to_detector_mm / lab.y());
  return {0.5 * (s.cols - 1) - hit.x() / s.pitch_mm, 0.5 * (s.rows - 1) - hit.z() / s.pitch_mm};
}

/// `<folder>/<name>.xtekct` and `<name>_0001.tif` ... (16-bit counts of `open_counts` white level).
inline std::filesystem::path write_nikon(const std::filesystem::path& folder, const NikonContent& c,
                                         const std::vector<Ball>& balls) {
  const ConeSetup& s = c.setup;
  std::filesystem::create_directories(folder);
  const std::filesystem::path file = folder / (c.name + ".xtekct");
  std::ofstream(file) << "[XTekCT]\nName=" << c.name << "\nInputFolderName=\nVoxelsX=64\nProjections=" << s.views
                      << "\nWhiteLevel=" << s.open_counts << "\nDetectorPixelsX=" << s.cols << "\nDetectorPixelsY=" << s.rows
                      << "\nDetectorPixelSizeX=" << s.pitch_mm << "\nDetectorPixelSizeY=" << s.pitch_mm
                      << "\nSrcToObject=" << s.source_to_axis_mm << "\nSrcToDetector=" << s.source_to_detector_mm
                      << "\nInitialAngle=" << c.initial_angle_deg << "\nAngularStep=" << c.angular_step_deg
                      << "\nObjectOffsetX=" << c.object_offset_x_mm << "\nObjectRoll=" << c.object_roll_deg
                      << "\nObjectTilt=" << c.object_tilt_deg << "\n[Xrays]\nXraykV=120\n";
  for (int k = 0; k < s.views; ++k) {
    Image image{s.cols, s.rows, std::vector<float>(static_cast<std::size_t>(s.cols * s.rows))};
    for (int j = 0; j < s.rows; ++j)
      for (int i = 0; i < s.cols; ++i) {
        const Eigen::Vector3d pixel((0.5 * (s.cols - 1) - i) * s.pitch_mm, s.source_to_detector_mm,
                                    (0.5 * (s.rows - 1) - j) * s.pitch_mm);
        const double p = ball_line_integral(Eigen::Vector3d::Zero(), pixel, balls,
                                            [&](const Eigen::Vector3d& b) { return nikon_lab(c, k, b); });
        image.pixels[static_cast<std::size_t>(j * s.cols + i)] = static_cast<float>(std::round(s.open_counts * std::exp(-p)));
      }
    char name[64];
    std::snprintf(name, sizeof name, "_%04d.tif", k + 1);
    write_image_uint16(image, folder / (c.name + name));
  }
  return file;
}

}  // namespace ctk::testing

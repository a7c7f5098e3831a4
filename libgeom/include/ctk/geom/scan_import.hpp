#pragma once
// Scans described elsewhere, turned into ctk-scan/1 with a "matrices" pose source (and its
// ctk-geometry/1 file): a circular orbit given by its numbers, or per-view ASTRA cone_vec rows.
// The matrices address the pixels of the files as stored, so a dataset whose loader reorients
// its images (the CWI walnuts: transpose of the up-down flip) needs no converted copies.
#include <Eigen/Core>
#include <filesystem>
#include <string>
#include <vector>

#include "ctk/geom/astra.hpp"
#include "ctk/geom/geometry_file.hpp"
#include "ctk/geom/scan.hpp"

namespace ctk {

/// A circular orbit by its numbers. Volume frame: the rotation axis is +z through the origin.
/// View k at t = sense * angle_k has its source at SOD (sin t, cos t, 0); detector columns run
/// along (cos t, -sin t, 0) and rows along -z (row 0 at the top); the central ray (perpendicular
/// from the source to the detector) meets it at the principal point, and the rotation axis
/// projects onto column u0 of that point. A one-row detector (a fan-beam scan) is allowed.
struct CircularOrbit {
  Detector detector;
  Eigen::Vector2d principal_point_px{0, 0};
  double source_to_axis_mm = 0;
  double source_to_detector_mm = 0;
  std::vector<double> angles_rad;
  int sense = +1;  // +1 or -1
};

/// Throws std::invalid_argument on non-positive or non-finite distances and pitches, SDD <= SOD, no
/// angles, an angle not finite or a bad sense; the matrices also when the numbers describe no projection.
std::vector<ConeVec> circular_cone_vecs(const CircularOrbit& orbit);
/// The same views as projection matrices.
std::vector<ProjectionMatrix> circular_matrices(const CircularOrbit& orbit);

/// How a stored image file relates to the image its geometry describes.
enum class StoredOrientation {
  as_described,
  transposed_flipped,  // described = transpose(flipud(stored)), i.e. described[r][c] = stored[H-1-c][r]
};
StoredOrientation stored_orientation_from_string(const std::string& name);  // "as-described" | "transpose-flipud"

/// The stored file's detector (columns and rows swap when transposed).
Detector stored_detector(StoredOrientation orientation, const Detector& described);
/// Homogeneous 3x3 map from described pixel coordinates (u, v) to stored ones.
Eigen::Matrix3d described_to_stored(StoredOrientation orientation, const Detector& described);

/// The scan file and geometry file of an imported scan, ready to write.
struct ImportedScan {
  ScanDescription scan;
  Geometry geometry;
};

/// `matrices` address stored pixels of `detector`, one per projection. The scan's summary
/// intrinsics (SDD, principal point: informative only for a matrices scan) come from the first
/// view. File names are made relative to `scan_file`'s folder.
ImportedScan import_matrices(const Detector& detector, const std::vector<ProjectionMatrix>& matrices, ProjectionSet projections,
                             const std::filesystem::path& scan_file);

/// Writes the geometry beside the scan (`<stem>.matrices.json`), then the scan, both atomically.
void write_imported_scan(const ImportedScan& imported, const std::filesystem::path& scan_file);

}  // namespace ctk

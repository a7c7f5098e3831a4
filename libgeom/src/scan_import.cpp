#include "ctk/geom/scan_import.hpp"

#include <cmath>
#include <sstream>
#include <stdexcept>
#include <string>

#include "ctk/core/atomic_write.hpp"

namespace ctk {

namespace fs = std::filesystem;

std::vector<ConeVec> circular_cone_vecs(const CircularOrbit& orbit) {
  const double sod = orbit.source_to_axis_mm, sdd = orbit.source_to_detector_mm;
  if (!(sod > 0 && sdd > sod)) throw std::invalid_argument("circular orbit: need 0 < SOD < SDD");
  if (orbit.angles_rad.empty()) throw std::invalid_argument("circular orbit: no angles");
  if (orbit.sense != 1 && orbit.sense != -1) throw std::invalid_argument("circular orbit: the sense must be +1 or -1");
  const Detector& det = orbit.detector;
  if (!(det.pitch_u_mm > 0 && det.pitch_v_mm > 0 && std::isfinite(det.pitch_u_mm) && std::isfinite(det.pitch_v_mm)))
    throw std::invalid_argument("circular orbit: the pixel pitch must be finite and above 0");
  if (!orbit.principal_point_px.allFinite() || !std::isfinite(sdd))
    throw std::invalid_argument("circular orbit: the principal point and the distances must be finite");
  // The principal point's offset from the detector's centre, in mm along columns and rows.
  const Eigen::Vector2d offset_mm =
      (det.centre_px() - orbit.principal_point_px).cwiseProduct(Eigen::Vector2d(det.pitch_u_mm, det.pitch_v_mm));
  std::vector<ConeVec> vecs;
  for (std::size_t k = 0; k < orbit.angles_rad.size(); ++k) {
    const double t = orbit.sense * orbit.angles_rad[k];
    if (!std::isfinite(t))
      throw std::invalid_argument("circular orbit: view " + std::to_string(k) +
                                  "'s angle is not finite (first + k step overflows)");
    const Eigen::Vector3d towards_source(std::sin(t), std::cos(t), 0.0);
    const Eigen::Vector3d e_u(std::cos(t), -std::sin(t), 0.0), e_v(0, 0, -1);
    const Eigen::Vector3d s = sod * towards_source;
    const Eigen::Vector3d d = -(sdd - sod) * towards_source + offset_mm.x() * e_u + offset_mm.y() * e_v;
    const Eigen::Vector3d u = det.pitch_u_mm * e_u, v = det.pitch_v_mm * e_v;
    vecs.push_back(make_cone_vec(s, d, u, v));
  }
  return vecs;
}

std::vector<ProjectionMatrix> circular_matrices(const CircularOrbit& orbit) {
  std::vector<ProjectionMatrix> out;
  for (const ConeVec& v : circular_cone_vecs(orbit)) {
    try {
      out.push_back(from_cone_vec(v, orbit.detector));
    } catch (const std::invalid_argument&) {
      // Finite numbers, yet no matrix: the focal length in pixels is negligible (or beyond double
      // precision) against the principal point, i.e. a pitch or distance in the wrong unit.
      const Detector& det = orbit.detector;
      std::ostringstream what;
      what << "circular orbit: a focal length of " << orbit.source_to_detector_mm / det.pitch_u_mm << " x "
           << orbit.source_to_detector_mm / det.pitch_v_mm << " px (SDD " << orbit.source_to_detector_mm << " mm over pitch "
           << det.pitch_u_mm << " x " << det.pitch_v_mm << " mm) with the principal point at (" << orbit.principal_point_px.x()
           << ", " << orbit.principal_point_px.y()
           << ") px describes no cone-beam projection: are the pitch and distances in mm?";
      throw std::invalid_argument(what.str());
    }
  }
  return out;
}

StoredOrientation stored_orientation_from_string(const std::string& name) {
  if (name == "as-described") return StoredOrientation::as_described;
  if (name == "transpose-flipud") return StoredOrientation::transposed_flipped;
  throw std::invalid_argument("unknown image orientation '" + name + "' (expected as-described or transpose-flipud)");
}

Detector stored_detector(StoredOrientation orientation, const Detector& described) {
  if (orientation == StoredOrientation::as_described) return described;
  return Detector{described.rows, described.cols, described.pitch_v_mm, described.pitch_u_mm};
}

Eigen::Matrix3d described_to_stored(StoredOrientation orientation, const Detector& described) {
  if (orientation == StoredOrientation::as_described) return Eigen::Matrix3d::Identity();
  // described[r][c] = stored[cols - 1 - c][r]: stored column = r, stored row = cols - 1 - c.
  Eigen::Matrix3d A;
  A << 0, 1, 0, -1, 0, described.cols - 1, 0, 0, 1;
  return A;
}

ImportedScan import_matrices(const Detector& detector, const std::vector<ProjectionMatrix>& matrices, ProjectionSet projections,
                             const fs::path& scan_file) {
  if (static_cast<int>(matrices.size()) != projections.count)
    throw std::invalid_argument("import: " + std::to_string(matrices.size()) + " matrices for " +
                                std::to_string(projections.count) + " projections");
  const fs::path folder = fs::absolute(scan_file).parent_path();
  auto relative = [&](const std::string& name) { return fs::absolute(name).lexically_proximate(folder).string(); };
  if (!projections.files_pattern.empty()) projections.files_pattern = relative(projections.files_pattern);
  for (auto& n : projections.file_names) n = relative(n);
  for (auto& n : projections.flat) n = relative(n);
  for (auto& n : projections.dark) n = relative(n);

  ImportedScan out;
  ScanDescription& scan = out.scan;
  scan.folder = folder;
  scan.detector = detector;
  scan.projections = projections;

  out.geometry.detector = detector;
  out.geometry.origin = "nominal";
  for (int i = 0; i < projections.count; ++i) {
    GeometryView v;
    v.index = i;
    v.projection = projections.file_name(i);
    v.P = matrices[static_cast<std::size_t>(i)];
    out.geometry.views.push_back(v);
  }
  scan.matrices = MatricesPoseSource{fs::path(scan_file).stem().string() + ".matrices.json", out.geometry};
  state_matrices_intrinsics(scan);
  return out;
}

void write_imported_scan(const ImportedScan& imported, const fs::path& scan_file) {
  write_geometry(imported.geometry, imported.scan.resolve(imported.scan.matrices->file));
  write_scan(imported.scan, scan_file);
}

}  // namespace ctk

#include "ctk/recon/measurements.hpp"

#include <algorithm>
#include <iomanip>
#include <optional>
#include <sstream>

#include "ctk/geom/error.hpp"
#include "ctk/proj/parallel.hpp"
#include "ctk/recon/detector_undistortion.hpp"

namespace ctk {

Measurements load_measurements(const ScanDescription& scan, const Geometry& geometry, const MeasurementOptions& options,
                               const std::function<void(int, int)>& progress) {
  const Detector& d = scan.detector;
  if (geometry.detector.cols != d.cols || geometry.detector.rows != d.rows)
    throw InputError(geometry.source(), json_key("detector"),
                     std::to_string(geometry.detector.cols) + " x " + std::to_string(geometry.detector.rows) +
                         " pixels, but the scan's detector is " + std::to_string(d.cols) + " x " + std::to_string(d.rows));
  Measurements m;
  for (int i : geometry.ok_views()) {
    const GeometryView& v = geometry.views[static_cast<std::size_t>(i)];
    if (v.index < 0 || v.index >= scan.projections.count)
      throw InputError(geometry.source(), json_key("views[" + std::to_string(i) + "].index"),
                       "view " + std::to_string(v.index) + " is not in the scan (0 .. " +
                           std::to_string(scan.projections.count - 1) + ")");
    m.view_indices.push_back(v.index);
    m.matrices.push_back(*v.P);
  }
  const int n = static_cast<int>(m.view_indices.size());
  const bool counts = scan.projections.kind == ProjectionKind::counts;
  m.line_integrals = ProjectionStack(n, d.rows, d.cols);
  if (counts && options.statistical_weights) m.weights = ProjectionStack(n, d.rows, d.cols);
  std::optional<DetectorUndistortion> undistortion;
  if (scan.distortion) {
    std::ostringstream note;
    note << "the scan declares a radial detector distortion (k1 " << scan.distortion->k1_per_px2 << " per px^2 about ("
         << scan.distortion->centre_px.x() << ", " << scan.distortion->centre_px.y() << ")); ";
    if (options.undistort) {
      undistortion.emplace(d.cols, d.rows, *scan.distortion);
      note << "the images are resampled onto the matrices' pinhole grid (largest shift " << std::setprecision(3)
           << undistortion->largest_shift_px() << " px";
      if (const int off = undistortion->pixels_measured_outside(); off > 0)
        note << "; " << off << " pixels per view were measured off the detector and "
             << (m.weights.views ? "get weight zero" : "repeat its edge");
      note << ")";
    } else {
      note << "the images are used as measured (the projector is a pinhole)";
    }
    m.distortion_note = note.str();
  }
  const std::optional<FlatDark> flat_dark = read_flat_dark(scan);
  std::vector<std::size_t> clamped(static_cast<std::size_t>(n), 0);
  int done = 0;
  // Reading is I/O bound and OpenImageIO is thread safe: a few images at a time.
  parallel_for_dynamic(n, [&](int k) {
    const Image image = read_line_integrals(scan, m.view_indices[static_cast<std::size_t>(k)], flat_dark,
                                            m.weights.views ? m.weights.view(k) : nullptr, &clamped[static_cast<std::size_t>(k)]);
    if (!undistortion) {
      std::copy(image.pixels.begin(), image.pixels.end(), m.line_integrals.view(k));
    } else {
      undistortion->apply(image.pixels.data(), m.line_integrals.view(k), DetectorUndistortion::Outside::nearest_edge);
      if (m.weights.views) {
        const std::vector<float> measured(m.weights.view(k), m.weights.view(k) + image.pixels.size());
        undistortion->apply(measured.data(), m.weights.view(k), DetectorUndistortion::Outside::zero);
      }
    }
#pragma omp critical(ctk_measurements_progress)
    if (progress) progress(++done, n);
  });
  for (int k = 0; k < n; ++k) {
    const std::size_t c = clamped[static_cast<std::size_t>(k)];
    m.clamped_pixels += c;
    if (c > 0)
      m.notes.push_back("view " + std::to_string(m.view_indices[static_cast<std::size_t>(k)]) + ": " + std::to_string(c) +
                        " pixels clamped (counts at or below dark, or above the flat)");
  }
  return m;
}

}  // namespace ctk

#include "ctk/recon/measurements.hpp"

#include <algorithm>
#include <cmath>

#include "ctk/geom/error.hpp"
#include "ctk/proj/parallel.hpp"

namespace ctk {

void counts_to_line_integrals(const Image& counts, const Image& flat, const Image& dark, float* p, float* w,
                              std::size_t& clamped) {
  // A transmission above 1.5 cannot come from attenuation: treat it like one at or below zero.
  constexpr double kMinCounts = 0.5, kMaxTransmission = 1.5;
  for (std::size_t i = 0; i < counts.pixels.size(); ++i) {
    const double open = double(flat.pixels[i]) - double(dark.pixels[i]);
    const double detected = double(counts.pixels[i]) - double(dark.pixels[i]);
    double t = open > 0 ? std::max(detected, kMinCounts) / open : kMaxTransmission;
    if (open <= 0 || detected < kMinCounts || t > kMaxTransmission) {
      ++clamped;
      t = std::clamp(t, kMinCounts / std::max(open, 1.0), kMaxTransmission);
    }
    p[i] = static_cast<float>(-std::log(t));
    if (w) w[i] = static_cast<float>(open > 0 ? std::max(detected, kMinCounts) / open : 0.0);
  }
}

Measurements load_measurements(const ScanDescription& scan, const Geometry& geometry, const MeasurementOptions& options,
                               const std::function<void(int, int)>& progress) {
  const Detector& d = scan.detector;
  if (geometry.detector.cols != d.cols || geometry.detector.rows != d.rows)
    throw InputError("geometry", "detector", "is " + std::to_string(geometry.detector.cols) + " x " +
                                                 std::to_string(geometry.detector.rows) + ", the scan's is " +
                                                 std::to_string(d.cols) + " x " + std::to_string(d.rows));
  Measurements m;
  for (int i : geometry.ok_views()) {
    const GeometryView& v = geometry.views[static_cast<std::size_t>(i)];
    if (v.index < 0 || v.index >= scan.projections.count)
      throw InputError("geometry", "views[" + std::to_string(i) + "].index",
                       "view " + std::to_string(v.index) + " is not in the scan (0 .. " +
                           std::to_string(scan.projections.count - 1) + ")");
    m.view_indices.push_back(v.index);
    m.matrices.push_back(*v.P);
  }
  const int n = static_cast<int>(m.view_indices.size());
  const bool counts = scan.projections.kind == ProjectionKind::counts;
  m.line_integrals = ProjectionStack(n, d.rows, d.cols);
  if (counts && options.statistical_weights) m.weights = ProjectionStack(n, d.rows, d.cols);
  Image flat, dark;
  if (counts) {
    flat = read_image(scan.resolve(scan.projections.flat), d.cols, d.rows);
    dark = read_image(scan.resolve(scan.projections.dark), d.cols, d.rows);
  }
  std::vector<std::size_t> clamped(static_cast<std::size_t>(n), 0);
  int done = 0;
  // Reading is I/O bound and OpenImageIO is thread safe: a few images at a time.
  parallel_for_dynamic(n, [&](int k) {
    const Image image = read_image(scan.projection_path(m.view_indices[static_cast<std::size_t>(k)]), d.cols, d.rows);
    float* p = m.line_integrals.view(k);
    if (counts) {
      counts_to_line_integrals(image, flat, dark, p, m.weights.views ? m.weights.view(k) : nullptr,
                               clamped[static_cast<std::size_t>(k)]);
    } else {
      std::copy(image.pixels.begin(), image.pixels.end(), p);
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

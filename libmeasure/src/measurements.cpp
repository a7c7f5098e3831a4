#include "ctk/measure/measurements.hpp"

#include <algorithm>
#include <iomanip>
#include <optional>
#include <sstream>

#include "ctk/core/error.hpp"
#include "ctk/core/parallel.hpp"
#include "ctk/measure/detector_undistortion.hpp"

namespace ctk {

namespace {

// The stack without the views not in `kept` (ascending stack positions).
void keep_views(Measurements& m, const std::vector<int>& kept) {
  const auto n = static_cast<int>(kept.size());
  auto compact = [&](ProjectionStack& stack) {
    if (stack.views == 0) return;
    ProjectionStack out(n, stack.rows, stack.cols);
    for (int k = 0; k < n; ++k) std::copy_n(stack.view(kept[static_cast<std::size_t>(k)]), stack.pixels_per_view(), out.view(k));
    stack = std::move(out);
  };
  compact(m.line_integrals);
  compact(m.weights);
  std::vector<int> indices;
  std::vector<ProjectionMatrix> matrices;
  for (int k : kept) {
    indices.push_back(m.view_indices[static_cast<std::size_t>(k)]);
    matrices.push_back(m.matrices[static_cast<std::size_t>(k)]);
  }
  m.view_indices = std::move(indices);
  m.matrices = std::move(matrices);
}

// The geometry's ok views this share reads (their scan indices and matrices into `m`, their
// positions among the ok views into `positions`), each checked against the scan; returns the
// number of ok views.
int select_views(const ScanDescription& scan, const Geometry& geometry, const MeasurementOptions& options, Measurements& m,
                 std::vector<int>& positions) {
  int position = -1;           // among the ok views
  std::vector<int> described;  // the scan views of the ok views so far
  for (int i : geometry.ok_views()) {
    ++position;
    const GeometryView& v = geometry.views[static_cast<std::size_t>(i)];
    if (v.index < 0 || v.index >= scan.projections.count)
      throw InputError(
          geometry.source(), json_key("views[" + std::to_string(i) + "].index"),
          "view " + std::to_string(v.index) + " is not in the scan (0 .. " + std::to_string(scan.projections.count - 1) + ")");
    const std::string key = "views[" + std::to_string(i) + "]";
    if (std::find(described.begin(), described.end(), v.index) != described.end())
      throw InputError(geometry.source(), json_key(key + ".index"), "view " + std::to_string(v.index) + " is described twice");
    // p2 is the depth in mm (the matrices are normalised): the holder origin, where the volume is
    // centred, must lie in front of the source.
    if (!(v.P->matrix()(2, 3) > 0))
      throw InputError(geometry.source(), json_key(key + ".P"),
                       "puts the holder origin " + std::to_string(v.P->matrix()(2, 3)) +
                           " mm from the source along the beam (behind it): "
                           "a matrix of the wrong sign?");
    described.push_back(v.index);
    if (position % options.shares != options.share) continue;
    positions.push_back(position);
    m.view_indices.push_back(v.index);
    m.matrices.push_back(*v.P);
  }
  return position + 1;
}

// A declared radial distortion: the resampling onto the matrices' pinhole grid (when asked), and
// what was done in `m.distortion_note`.
std::optional<DetectorUndistortion> undistortion_for(const ScanDescription& scan, const MeasurementOptions& options,
                                                     Measurements& m) {
  std::optional<DetectorUndistortion> undistortion;
  if (!scan.distortion) return undistortion;
  const Detector& d = scan.detector;
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
  return undistortion;
}

// Each view's clamped and non-finite pixels counted and noted; a view with too many non-finite
// pixels left out.
void count_and_leave_out(const std::vector<std::size_t>& clamped, const std::vector<std::size_t>& masked, std::size_t pixels,
                         Measurements& m) {
  std::vector<int> kept;
  const int n = static_cast<int>(m.view_indices.size());
  for (int k = 0; k < n; ++k) {
    const auto i = static_cast<std::size_t>(k);
    const std::string view = "view " + std::to_string(m.view_indices[i]) + ": ";
    m.clamped_pixels += clamped[i];
    if (clamped[i] > 0)
      m.notes.push_back(view + std::to_string(clamped[i]) + " pixels clamped (counts at or below dark, or above the flat)");
    if (static_cast<double>(masked[i]) > kMostMaskedFraction * static_cast<double>(pixels)) {
      m.left_out.push_back(view + std::to_string(masked[i]) + " of " + std::to_string(pixels) +
                           " pixels are not finite numbers (NaN or infinite): left out");
      continue;
    }
    m.masked_pixels += masked[i];
    if (masked[i] > 0) m.notes.push_back(view + std::to_string(masked[i]) + " pixels not finite (NaN or infinite): masked");
    kept.push_back(k);
  }
  if (static_cast<int>(kept.size()) < n) keep_views(m, kept);
}

}  // namespace

void MeasurementOptions::validate() const {
  require_option(shares >= 1, "MeasurementOptions.shares", "at least 1", shares);
  require_option(share >= 0 && share < shares, "MeasurementOptions.share", "a number in 0 .. shares - 1", share);
  if (rows) {
    require_option(rows->height >= 1, "MeasurementOptions.rows.height", "at least 1", rows->height);
    for (std::size_t k = 0; k < rows->first.size() && k < rows->count.size(); ++k)
      require_option(rows->first[k] >= 0 && rows->count[k] >= 0 && rows->count[k] <= rows->height, "MeasurementOptions.rows",
                     "windows within the stacks' height, from row 0 on", rows->count[k]);
  }
}

Measurements load_measurements(const ScanDescription& scan, const Geometry& geometry, const MeasurementOptions& options,
                               const std::function<void(int, int)>& progress) {
  const Detector& d = scan.detector;
  if (geometry.detector.cols != d.cols || geometry.detector.rows != d.rows)
    throw InputError(geometry.source(), json_key("detector"),
                     std::to_string(geometry.detector.cols) + " x " + std::to_string(geometry.detector.rows) +
                         " pixels, but the scan's detector is " + std::to_string(d.cols) + " x " + std::to_string(d.rows));
  options.validate();
  Measurements m;
  std::vector<int> positions;  // each view read: its position among the ok views
  const int ok_views = select_views(scan, geometry, options, m, positions);
  const int n = static_cast<int>(m.view_indices.size());
  const bool counts = scan.projections.kind == ProjectionKind::counts;
  const std::optional<MeasurementOptions::RowWindow>& window = options.rows;
  if (window && (static_cast<int>(window->first.size()) != ok_views || window->count.size() != window->first.size()))
    throw std::invalid_argument("load_measurements: the row window does not have one entry per ok view");
  if (window)
    for (std::size_t k = 0; k < window->first.size(); ++k)
      if (window->first[k] + window->count[k] > d.rows)
        throw std::invalid_argument("load_measurements: a row window reaches beyond the detector's " + std::to_string(d.rows) +
                                    " rows");
  const int height = window ? window->height : d.rows;
  m.line_integrals = ProjectionStack(n, height, d.cols);
  if (counts && options.statistical_weights) m.weights = ProjectionStack(n, height, d.cols);
  const std::optional<DetectorUndistortion> undistortion = undistortion_for(scan, options, m);
  const std::optional<FlatDark> flat_dark = read_flat_dark(scan);
  std::vector<std::size_t> clamped(static_cast<std::size_t>(n), 0), masked(static_cast<std::size_t>(n), 0);
  int done = 0;
  // Reading is I/O bound and OpenImageIO is thread safe: a few images at a time.
  const std::size_t full_pixels = static_cast<std::size_t>(d.rows) * static_cast<std::size_t>(d.cols);
  parallel_for_dynamic(n, [&](int k) {
    // A whole image goes straight into its stack view; a window's rows through full-size buffers.
    std::vector<float> full(window ? full_pixels : 0), full_weights(window && m.weights.views ? full_pixels : 0);
    float* li = window ? full.data() : m.line_integrals.view(k);
    float* w = !m.weights.views ? nullptr : window ? full_weights.data() : m.weights.view(k);
    const Image image = read_line_integrals(scan, m.view_indices[static_cast<std::size_t>(k)], flat_dark, w,
                                            &clamped[static_cast<std::size_t>(k)], &masked[static_cast<std::size_t>(k)]);
    if (!undistortion) {
      std::copy(image.pixels.begin(), image.pixels.end(), li);
    } else {
      undistortion->apply(image.pixels.data(), li, DetectorUndistortion::Outside::nearest_edge);
      if (w) {
        const std::vector<float> measured(w, w + full_pixels);
        undistortion->apply(measured.data(), w, DetectorUndistortion::Outside::zero);
      }
    }
    if (window) {
      const auto at = static_cast<std::size_t>(positions[static_cast<std::size_t>(k)]);
      const std::size_t begin = static_cast<std::size_t>(window->first[at]) * static_cast<std::size_t>(d.cols),
                        values = static_cast<std::size_t>(window->count[at]) * static_cast<std::size_t>(d.cols);
      std::copy_n(full.begin() + static_cast<std::ptrdiff_t>(begin), values, m.line_integrals.view(k));
      if (w) std::copy_n(full_weights.begin() + static_cast<std::ptrdiff_t>(begin), values, m.weights.view(k));
    }
#pragma omp critical(ctk_measurements_progress)
    if (progress) progress(++done, n);
  });
  count_and_leave_out(clamped, masked, full_pixels, m);
  return m;
}

namespace {

// Moves the views at `positions` (ascending) of `from` into `to`, and compacts the rest of `from`.
void split_stack(ProjectionStack& from, const std::vector<int>& positions, ProjectionStack& to) {
  if (from.views == 0) return;
  const std::size_t n = from.pixels_per_view();
  to = ProjectionStack(static_cast<int>(positions.size()), from.rows, from.cols);
  int kept = 0;
  std::size_t next = 0;
  for (int v = 0; v < from.views; ++v) {
    if (next < positions.size() && positions[next] == v) {
      std::copy_n(from.view(v), n, to.view(static_cast<int>(next++)));
      continue;
    }
    if (kept != v) std::copy_n(from.view(v), n, from.view(kept));
    ++kept;
  }
  from.views = kept;
  from.data.resize(static_cast<std::size_t>(kept) * n);
}

}  // namespace

Measurements take_views(Measurements& m, const std::vector<int>& positions) {
  const int views = static_cast<int>(m.view_indices.size());
  for (std::size_t k = 0; k < positions.size(); ++k)
    if (positions[k] < 0 || positions[k] >= views || (k > 0 && positions[k] <= positions[k - 1]))
      throw std::invalid_argument("take_views: positions must ascend within the " + std::to_string(views) + " views");
  Measurements out;
  split_stack(m.line_integrals, positions, out.line_integrals);
  split_stack(m.weights, positions, out.weights);
  std::vector<int> kept_indices;
  std::vector<ProjectionMatrix> kept_matrices;
  std::size_t next = 0;
  for (int v = 0; v < views; ++v) {
    const std::size_t k = static_cast<std::size_t>(v);
    if (next < positions.size() && positions[next] == v) {
      out.view_indices.push_back(m.view_indices[k]);
      out.matrices.push_back(m.matrices[k]);
      ++next;
    } else {
      kept_indices.push_back(m.view_indices[k]);
      kept_matrices.push_back(m.matrices[k]);
    }
  }
  m.view_indices = std::move(kept_indices);
  m.matrices = std::move(kept_matrices);
  return out;
}

void require_views_left(const Measurements& m, const std::string& geometry_source) {
  if (m.view_indices.empty() && !m.left_out.empty())
    throw InputError(geometry_source, json_key("views"), "every ok view was left out: " + m.left_out.front());
}

}  // namespace ctk

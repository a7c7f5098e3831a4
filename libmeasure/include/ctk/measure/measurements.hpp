#pragma once
// From a scan and its geometry to what the solvers consume: the line integrals b of the views
// that are "ok", their matrices, and statistical weights. Counts become line integrals
// -log((I - dark) / (flat - dark)); non-positive or over-flat values are clamped and counted. A
// declared radial detector distortion is undone by resampling (DetectorUndistortion).
#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "ctk/core/projection_stack.hpp"
#include "ctk/geom/geometry_file.hpp"
#include "ctk/geom/scan.hpp"
#include "ctk/measure/projection_reading.hpp"

namespace ctk {

struct Measurements {
  std::vector<int> view_indices;           // scan view index of each stack view
  std::vector<ProjectionMatrix> matrices;  // one per stack view
  ProjectionStack line_integrals;          // b
  ProjectionStack weights;                 // W: empty (views == 0) when unit weights
  std::size_t clamped_pixels = 0;          // counts at or below dark (or flat not above dark)
  std::size_t masked_pixels = 0;           // not finite (NaN, inf): weight 0, neighbours' mean
  std::vector<std::string> left_out;       // views of the geometry not used, each with the reason
  std::vector<std::string> notes;          // per-view findings worth a line in the log
  std::string distortion_note;             // what was done with a declared detector distortion; empty when none
};

struct MeasurementOptions {
  bool statistical_weights = true;  // only for counts; line-integral scans always get unit weights
  /// A declared detector.radial_distortion resamples every image onto the matrices' pinhole grid
  /// (DetectorUndistortion); false uses the images as measured.
  bool undistort = true;
  /// A run spread over ranks reads only its share of the ok views: those whose position among
  /// them is `share` modulo `shares` (every other ok view is still checked, not read).
  int share = 0, shares = 1;
  /// A rank holding a slab of the volume keeps only the rows it owns of each view: those of ok
  /// view k (its position among them) are rows [first[k], first[k] + count[k]), stored at the top
  /// of stacks `height` rows high (zeros below). Empty: whole images.
  struct RowWindow {
    std::vector<int> first, count;
    int height = 0;
  };
  std::optional<RowWindow> rows = std::nullopt;
  void validate() const;  // std::invalid_argument naming the field
};

/// Share of a view's pixels that may be masked (not finite) before the view is left out: beyond
/// it the neighbours' mean no longer stands for the lost measurements.
constexpr double kMostMaskedFraction = 0.01;

/// Reads every "ok" view of `geometry` (others are not used); throws InputError naming the image
/// that cannot be read or has the wrong size. A view with more than kMostMaskedFraction of its
/// pixels not finite is left out (`left_out` says why); fewer are masked and counted.
/// `progress(done, total)` after each image.
Measurements load_measurements(const ScanDescription& scan, const Geometry& geometry, const MeasurementOptions& options = {},
                               const std::function<void(int, int)>& progress = {});

/// Moves the stack views at `positions` (ascending, each < the stack's views) out of `m` into the
/// result, which also carries their indices and matrices; `m` keeps the others in their order,
/// compacted in place (its buffers are not reallocated). Counts and notes stay with `m`.
Measurements take_views(Measurements& m, const std::vector<int>& positions);

/// Throws InputError naming `geometry_source` (key "views") when views were left out and none
/// remains to reconstruct from.
void require_views_left(const Measurements& m, const std::string& geometry_source);

}  // namespace ctk

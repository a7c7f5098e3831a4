#pragma once
// The markerless workflow on a whole scan, as `ctk refine` and `ctk.refine` run it: read the ok
// views, build the held-out yardstick on a coarse grid, start the detector offset's scan where
// conjugate rays put the axis (full circles), run the loop, and return the refined geometry with
// the report. Files are the caller's: nothing here writes.
#include <functional>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "ctk/geom/geometry_file.hpp"
#include "ctk/geom/scan.hpp"
#include "ctk/recon/conjugate_rays.hpp"
#include "ctk/recon/markerless_refinement.hpp"
#include "ctk/recon/repeat_exposure.hpp"

namespace ctk {

struct RefineScanOptions {
  double coarsening = 2.0;           // voxel of the held-out predictions, in pixels seen at the axis
  double blur_arc_deg = 0;           // arc each view is known to integrate (the blur scan's range)
  double z_accept = 3.0;             // acceptance: held-out improvement in standard errors
  std::vector<std::string> effects;  // candidates; empty: all of RefinementOptions
  void validate() const;             // std::invalid_argument naming the field
};

struct RefineScanSummary {
  RefinementResult result;
  std::optional<ConjugateRayEstimate> conjugate;      // the axis' column from conjugate rays, if the scan allows
  std::string conjugate_why_not;                      // why there is none
  std::optional<RepeatExposure> repeat;               // the last view against the first, at the same angle
  double loop_u0_px = 0;                              // the axis' column the loop found (nominal when not refined)
  Geometry refined;                                   // the geometry given, its ok views' matrices refined
  std::size_t clamped_pixels = 0, masked_pixels = 0;  // counts at or below dark; not finite (weight 0)
  std::vector<std::string> left_out;                  // views not used, with the reason
  double seconds = 0;
  /// The loop's stated uncertainty of the axis' column (0 when the detector offset was not fitted):
  /// its views' scatter, or (`covering`) the larger of that and its halves in time's spread.
  double loop_u0_sigma_px(bool covering = false) const;
  /// ctk-diagnosis/1 (mode "markerless") with the cross-check; the caller adds file names.
  nlohmann::json report() const;
  /// One line: held-out RMS before -> after and the effects accepted.
  std::string brief() const;
};

/// `log` receives one line per step; `reading(done, total)` follows the images as they are read.
RefineScanSummary refine_scan(const ScanDescription& scan, Geometry geometry, const RefineScanOptions& options,
                              const std::function<void(const std::string&)>& log = {},
                              const std::function<void(int, int)>& reading = {});

}  // namespace ctk

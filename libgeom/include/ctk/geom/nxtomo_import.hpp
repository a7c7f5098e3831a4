#pragma once
// An NXtomo file (nexus_tomo.hpp) as a ctk scan: its frames copied out as TIFF files (the scan
// contract names one file per view), projections, flats and darks by their image key, a circular
// orbit from the rotation angles. NXtomo itself describes a parallel beam; the cone's distances come
// from the file where it has them (NXsource/distance, NXdetector/distance) or from the caller.
// Frame and lab conventions (NeXus' McStas frame: z along the beam, y up): the frames are
// [rows][cols] with row 0 at the top and columns running along +x (to the left looking
// downstream); the sample turns right-handed about +y by the rotation angle (sense +1).
#include <Eigen/Core>
#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "ctk/core/nexus_tomo.hpp"
#include "ctk/geom/scan_import.hpp"

namespace ctk {

/// What the caller gives; each overrides the file.
struct NxTomoSetup {
  std::optional<double> source_to_axis_mm, source_to_detector_mm;
  std::optional<Eigen::Vector2d> pitch_mm, principal_point_px;
  int sense = +1;
  /// The frames are line integrals already (float data, no flats needed).
  bool line_integrals = false;
};

struct NxTomoPlan {
  CircularOrbit orbit;
  std::vector<int> projections, flats, darks;  // frame indices
  bool line_integrals = false;
  std::vector<std::string> notes;  // what was taken from where, and what was assumed
};

/// Throws InputError naming the dataset (or the option to give) when a number is neither in the
/// file nor given, or when counts come without flat frames.
NxTomoPlan plan_nxtomo_import(const NxTomo& scan, const NxTomoSetup& setup);

/// Writes the frames under `<scan stem>.frames/` beside `scan_file` (16-bit TIFF for integer counts
/// up to 65535, float TIFF otherwise, each atomically) and returns the scan naming them.
ImportedScan import_nxtomo(const NxTomo& scan, const NxTomoPlan& plan, const std::filesystem::path& scan_file,
                           const std::function<void(int written, int total)>& progress = {});

}  // namespace ctk

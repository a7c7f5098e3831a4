#pragma once
// Nikon (X-Tek) cone-beam scans: an `.xtekct` text file of `Key=Value` lines beside a folder of
// TIFF projections. What it says, and how it places source, axis and detector, as CIL's reader
// documents it: the source at the origin, the beam along +y, z up; the rotation axis at
// (-ObjectOffsetX, SrcToObject, 0), tilted by ObjectTilt about x and rolled by ObjectRoll about y
// (or by the centre of rotation's drift from the top of the detector to its bottom); the
// detector's centre at (0, SrcToDetector, 0), its first pixel at the top right as seen from the
// source; view k at angle 180 deg - (InitialAngle + k AngularStep), the sample turning right-handed
// about the axis; counts normalised by WhiteLevel (no dark).
#include <filesystem>
#include <string>
#include <vector>

#include "ctk/geom/detector.hpp"
#include "ctk/geom/projection_matrix.hpp"

namespace ctk {

struct NikonScan {
  std::filesystem::path file;          // the .xtekct
  std::string name;                    // Name: the projections' file prefix ("" when not given)
  std::filesystem::path input_folder;  // InputFolderName resolved beside the file (the file's folder otherwise)
  int projections = 0;
  double white_level = 0;  // counts of the open beam
  Detector detector;       // DetectorPixelsX/Y, DetectorPixelSizeX/Y
  double source_to_object_mm = 0, source_to_detector_mm = 0;
  double initial_angle_deg = 0, angular_step_deg = 0;
  double axis_offset_mm = 0;  // ObjectOffsetX, or the centre of rotation's mean times the magnification's inverse
  double axis_roll_rad = 0, axis_tilt_rad = 0;
  std::vector<std::string> warnings;  // keys read but not modelled
};

/// Throws InputError naming the file and the key (or line) on a missing or malformed value.
NikonScan read_xtekct(const std::filesystem::path& file);

/// One matrix per projection, in the volume frame turning with the sample (its z along the
/// rotation axis, origin on the axis at the source's height). `sense` -1 turns the other way.
std::vector<ProjectionMatrix> nikon_matrices(const NikonScan& scan, int sense = +1);

/// The projection files: `<Name>_*.tif` (or every `.tif` when no Name is given) in the input
/// folder, in natural order. Throws InputError when their number is not `Projections`.
std::vector<std::filesystem::path> nikon_projection_files(const NikonScan& scan);

}  // namespace ctk

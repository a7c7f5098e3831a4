#pragma once
// Interchange with RTK's geometry XML (`RTKThreeDCircularGeometry`, versions 2 and 3): per view
// nine numbers (source to isocentre and to detector, gantry, out-of-plane and in-plane angles in
// degrees, source and projection offsets in mm), and the 3x4 matrix they make.
//
// RTK's matrix is M = T(sx - px, sy - py) Mag(sdd, sid) T(-sx, -sy, 0) R, with
// R = Rz(-in_plane) Rx(-out_of_plane) Ry(-gantry) turning the volume into the rotated frame, where
// the source sits at (sx, sy, sid), the detector plane at z = sid - sdd with its origin at
// (px, py), and Mag = [[-sdd, 0, 0, 0], [0, -sdd, 0, 0], [0, 0, 1, -sid]]. M maps volume mm to
// the detector's own coordinates (x, y) in mm.
//
// ctk's matrices map to pixels. The two meet on a detector of `cols x rows` pixels of
// (pitch_u, pitch_v), centred: x = (u - cu) pitch_u and y = +-(v - cv) pitch_v, (cu, cv) the
// detector centre. RTK's frame (x, y, and z towards the source) is right-handed, and so is
// ctk's camera (columns, rows, z towards the detector), so RTK's y runs against ctk's rows for
// a detector ctk sees as it is (every simulated or robot scan: RTK then reads the stack flipped
// vertically) and along them for one whose stored images are mirrored (RTK reads them as stored).
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "ctk/geom/detector.hpp"
#include "ctk/geom/projection_matrix.hpp"

namespace ctk {

/// How RTK's detector y relates to the stored rows.
enum class RtkRows {
  as_stored,  // y = (v - cv) pitch_v: RTK indexes the images as stored (identity direction)
  flipped,    // y = (cv - v) pitch_v: RTK indexes them flipped vertically (row 0 at the bottom)
};
const char* to_string(RtkRows rows);                    // "as-stored" | "flipped"
RtkRows rtk_rows_from_string(const std::string& name);  // throws std::invalid_argument
/// The sense under which RTK's parameters can hold P: flipped for a detector seen as it is,
/// as_stored for a mirrored one.
RtkRows rtk_rows_for(const ProjectionMatrix& P);

struct RtkProjection {
  double source_to_isocentre_mm = 0, source_to_detector_mm = 0;
  double gantry_deg = 0, out_of_plane_deg = 0, in_plane_deg = 0;
  double source_offset_x_mm = 0, source_offset_y_mm = 0;
  double projection_offset_x_mm = 0, projection_offset_y_mm = 0;
};

/// RTK's matrix of one view (volume mm to detector mm), as RTK composes it.
Matrix34d rtk_matrix(const RtkProjection& p);

/// The view as a ctk matrix on `detector`. Throws std::invalid_argument for a parallel or
/// reversed projection (source-to-detector distance <= 0).
ProjectionMatrix from_rtk(const RtkProjection& p, const Detector& detector, RtkRows rows);

/// RTK's parameters of a ctk matrix on `detector`. Throws std::invalid_argument when they cannot
/// hold it to 1e-6 px (a skewed or non-square pixel grid, or a detector mirrored under `rows`),
/// saying which.
RtkProjection to_rtk(const ProjectionMatrix& P, const Detector& detector, RtkRows rows);

/// RTK's circular geometry turns about its volume's y axis (rtkfdk weights and filters for that
/// axis), ctk's holder frame about z. Exports therefore put the holder's z on RTK's y: RTK (x, y, z)
/// = holder (x, z, -y), a turn of 90 degrees about x; a volume RTK reconstructs from them is the
/// holder's with y and z so exchanged. RTK's own files are read in their own frame.
/// The matrix of P (holder frame) for a volume in RTK's frame of a ctk export, and back.
ProjectionMatrix holder_matrix_in_rtk_frame(const ProjectionMatrix& P);
ProjectionMatrix rtk_frame_matrix_in_holder(const ProjectionMatrix& P);

struct RtkGeometry {
  std::vector<RtkProjection> views;
  std::optional<RtkRows> rows;  // the sense a file written by ctk names in its comment
  /// Whether the file says it was written by ctk with the holder's z on RTK's y (its matrices then
  /// map RTK's volume frame; rtk_frame_matrix_in_holder brings them back).
  bool holder_z_on_rtk_y = false;

  /// The sense to read the views under: the one the file names, else as_stored (RTK indexing
  /// the images as stored, as its own tools write them).
  RtkRows pixel_map() const { return rows.value_or(RtkRows::as_stored); }
};

/// Reads the views in order; a parameter outside a <Projection> holds for every projection after
/// it until one sets it anew (as RTK reads it). Where a projection carries its <Matrix>, it must
/// agree with the parameters. Throws InputError naming the file and the element.
RtkGeometry read_rtk_geometry(const std::filesystem::path& file);

/// Writes version 3 atomically, as RTK writes it: parameters equal over all views once, the rest
/// per projection, each projection with its matrix; 17 significant digits. A comment names the
/// pixel map under `rows`, and another the volume frame when `holder_z_on_rtk_y` (RTK ignores
/// both; read_rtk_geometry reads them back).
void write_rtk_geometry(const std::vector<RtkProjection>& views, RtkRows rows, const std::filesystem::path& file,
                        bool holder_z_on_rtk_y = false);

/// The matrices of a geometry file as ctk's holder frame sees them (a ctk export's frame undone).
std::vector<ProjectionMatrix> holder_matrices(const RtkGeometry& geometry, const Detector& detector, RtkRows rows);

}  // namespace ctk

#pragma once
// scan.json, format "ctk-scan/1": the nominal description of one scan (scan-format.md).
// read_scan() validates everything the contract requires and resolves paths against the file's
// folder; it never touches the projections themselves (a missing image is a per-view matter).
#include <Eigen/Core>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "ctk/geom/detector.hpp"
#include "ctk/geom/geometry_file.hpp"
#include "ctk/geom/helix.hpp"
#include "ctk/geom/joint_log.hpp"
#include "ctk/geom/rigid.hpp"

namespace ctk {

enum class ProjectionKind { counts, line_integrals };

struct ProjectionSet {
  std::string files_pattern;            // as written: printf pattern or empty when a list
  std::vector<std::string> file_names;  // as written when a list was given
  int count = 0;
  ProjectionKind kind = ProjectionKind::line_integrals;
  /// As written (required for counts). A list of several frames (e.g. flats taken before and
  /// after the scan) is averaged pixel by pixel: an extension of ctk-scan/1, one name stays a string.
  std::vector<std::string> flat, dark;
  /// Name of projection `view` as written in the file (relative to the scan folder).
  std::string file_name(int view) const;
};

struct PandaPoseSource {
  std::string joints_csv;  // as written
  Rigid T_camera_base = Rigid::Identity();
  Rigid T_flange_holder = Rigid::Identity();
  JointLog joints;  // loaded and checked against projections.count by read_scan
  /// Optional key (an extension of ctk-scan/1): encoder zero offsets, true angle = logged + offset.
  panda::Joints joint_offsets_rad{};
};

struct MatricesPoseSource {
  std::string file;   // a ctk-geometry/1 file, as written
  Geometry geometry;  // loaded by read_scan
};

struct ScanDescription {
  std::filesystem::path folder;  // where scan.json lives; relative names resolve against it
  Detector detector;
  Eigen::Vector2d principal_point_px{0, 0};
  double source_to_detector_mm = 0;
  ProjectionSet projections;
  std::optional<PandaPoseSource> panda;  // exactly one of panda / matrices is set
  std::optional<MatricesPoseSource> matrices;
  std::optional<Holder> holder;  // required for calibration, optional otherwise
  /// When `holder` names a ctk-holder/1 file instead of spelling the holder out (an extension of
  /// ctk-scan/1): that name, as written (resolved against `folder`), and the holder it gave. While
  /// `holder` is still that one the scan is written with the name; once a workflow changed it (a
  /// diagnosis moving spheres), spelt out.
  struct HolderFileReference {
    std::string name;
    Holder as_filed;
  };
  std::optional<HolderFileReference> holder_file;
  /// Optional key `detector.radial_distortion` {k1_per_px2, center_px} (an extension of
  /// ctk-scan/1, as the diagnosis reports it): the detector measures x at x + k1 |x - c|^2 (x - c).
  std::optional<RadialDistortion> distortion;
  /// Optional key `source_drift_mm_per_100_views` [x, y] (an extension of ctk-scan/1): the focal
  /// spot moves linearly with the view index, in camera x and y, the detector staying put.
  Eigen::Vector2d source_drift_mm_per_100_views{0, 0};
  /// Optional key `written_by` {"run": id} (an extension of ctk-scan/1): the ctk run that wrote the
  /// scan and its images at once (ctk simulate). Images that name another run are refused.
  std::string written_by_run;
  /// Optional key `detector.binning` (an extension of ctk-scan/1): every command works on b x b
  /// binned pixels. `detector`, `principal_point_px`, `distortion` and the matrices then describe
  /// the binned detector, `stored_detector` the images as stored (and as the file states them);
  /// the loader bins each image as it reads it (projection_reading.hpp).
  int binning = 1;
  Detector stored_detector;
  std::vector<std::string> warnings;  // unknown keys and other non-fatal findings

  Intrinsics intrinsics() const { return Intrinsics::from_setup(source_to_detector_mm, detector, principal_point_px); }
  /// Where the focal spot is at `view` (camera frame, mm), from the declared drift.
  Eigen::Vector3d source_offset_mm(int view) const {
    return drifted_focal_spot_mm(source_drift_mm_per_100_views.x(), source_drift_mm_per_100_views.y(), view);
  }
  std::filesystem::path resolve(const std::string& name) const;
  std::filesystem::path projection_path(int view) const { return resolve(projections.file_name(view)); }
};

/// The same scan written at `file`: every relative name (projections, flats, darks, joints,
/// matrices) rewritten so that it finds the same file from the new folder.
ScanDescription relocated_scan(const ScanDescription& scan, const std::filesystem::path& file);

/// A matrices scan's summary intrinsics (source-to-detector distance, principal point:
/// informative only) set to what its first view with a matrix encodes.
void state_matrices_intrinsics(ScanDescription& scan);

/// Bins the scan's detector by a further `factor` (b x b pixels become one): detector, principal
/// point, distortion and a matrices pose source follow. Throws std::invalid_argument when the factor
/// does not fit the detector.
void bin_scan(ScanDescription& scan, int factor);

/// A geometry for this scan's detector: one made for its stored pixels is binned as the images
/// are; one for the binned detector is taken as it is.
Geometry geometry_for_scan(const ScanDescription& scan, const Geometry& geometry);

/// Reads and validates; throws InputError naming the file and key on any violation, including
/// a referenced file (joints, flat, dark, matrices) that cannot be read.
ScanDescription read_scan(const std::filesystem::path& file);
/// The same checks on a document already in memory, as if it were at `file` (names resolve against
/// its folder, and errors name it).
ScanDescription scan_from_json(const nlohmann::json& root, const std::filesystem::path& file);
nlohmann::json scan_to_json(const ScanDescription& scan);

/// Which of a scan's projection files exist (paths taken lexically: the scan's folder may not exist
/// yet when a scan is being imported).
struct ProjectionCensus {
  int missing = 0;
  std::filesystem::path first_missing, first_present;
};
ProjectionCensus take_projection_census(const ScanDescription& scan);
/// Refuses (InputError on `file`, `key`) a scan none of whose projection files exists, or more
/// than half: a count that outnumbers the files on disk two to one is a wrong count or pattern, and
/// would otherwise become a million rejected views. A few missing files are each view's rejection.
ProjectionCensus require_projection_files(const ScanDescription& scan, const std::string& file, const std::string& key);
/// Writes atomically. Paths stay as written (relative to the scan's folder).
void write_scan(const ScanDescription& scan, const std::filesystem::path& file);

}  // namespace ctk

#pragma once
// The import workflow (`ctk import`, `ctk.import_scan`): a scan described by another tool becomes a
// ctk-scan/1 file with a "matrices" pose source and its ctk-geometry/1 file beside it
// (`<stem>.matrices.json`), so no one writes JSON by hand. Six sources: a circular orbit by its
// numbers, ASTRA cone_vec rows, RTK's geometry XML, matrices given by the caller, an NXtomo file
// (its frames copied out as TIFF into `<stem>.frames/`) and a Nikon .xtekct file (its white level
// and a zero dark written as images beside the scan, so the scan stays ctk-scan/1).
// Before anything is written the images are checked (some must exist, the first must have the
// detector's size; views whose files are missing are warned about, and calibrate and reconstruct
// reject them) and no output may be an input (run_files.hpp); the files are then written together
// (output_set.hpp) and the scan is read back as every command reads it.
#include <Eigen/Core>
#include <array>
#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "ctk/geom/nxtomo_import.hpp"
#include "ctk/geom/rtk_geometry.hpp"
#include "ctk/geom/scan.hpp"
#include "ctk/geom/scan_import.hpp"

namespace ctk {

/// What every import writes: the scan file (its matrices go beside it) and the binning it records
/// (detector.binning: every command then bins the images as it reads them).
struct ImportRequest {
  std::filesystem::path out;
  int bin = 1;
  /// How messages name a field (`sod_mm`, `files`, ...): by default as the request's member
  /// ("CircularImportRequest.sod_mm"); `ctk import` names its options, `ctk.import_scan` its keywords.
  std::function<std::string(const std::string& field)> field_names;
  /// `field`, a member of request type `type`, as messages name it.
  std::string name(const char* type, const char* field) const;
  void validate() const;  // std::invalid_argument naming the field
};

/// Projection files named by the caller (the circular, cone-vec, RTK and matrices imports).
struct ProjectionImportRequest : ImportRequest {
  std::vector<std::string> files;  // one printf pattern (with count), one quoted glob (natural order), or the names in view order
  int count = 0;                   // with a pattern: the views; otherwise 0 or the number of files
  ProjectionKind kind = ProjectionKind::counts;
  std::vector<std::string> flat, dark;         // counts: several are averaged
  std::optional<std::array<int, 2>> detector;  // columns, rows of the described image (default: the first file's)
  std::vector<double> pitch_mm;                // one value or u v
  void validate() const;
};

struct CircularImportRequest : ProjectionImportRequest {
  double sod_mm = 0, sdd_mm = 0;  // source to rotation axis, to detector
  double first_angle_deg = 0, step_deg = 0;
  std::optional<Eigen::Vector2d> principal_point_px;  // default: the detector centre
  int sense = +1;                                     // scan_import.hpp's CircularOrbit
  void validate() const;
};

struct ConeVecImportRequest : ProjectionImportRequest {  // pitch_mm default: the vectors' own steps
  std::filesystem::path vectors;                         // 12 numbers per line
  std::vector<int> vector_rows;                          // per projection (default: 0, 1, ...)
  StoredOrientation orientation = StoredOrientation::as_described;
  void validate() const;
};

struct RtkImportRequest : ProjectionImportRequest {
  std::filesystem::path geometry;  // RTKThreeDCircularGeometry, version 2 or 3
  std::optional<RtkRows> rows;     // default: what a file written by ctk names, else as-stored
  void validate() const;
};

/// Matrices the caller computed, addressing the stored pixels; `detector` and `pitch_mm` given.
struct MatricesImportRequest : ProjectionImportRequest {
  std::vector<ProjectionMatrix> matrices;  // one per projection
  void validate() const;
};

struct NxTomoImportRequest : ImportRequest {
  std::filesystem::path nexus;
  std::string entry;  // empty: the first NXentry whose definition is NXtomo
  NxTomoSetup setup;  // what overrides the file
  void validate() const;
};

struct NikonImportRequest : ImportRequest {
  std::filesystem::path xtekct;  // the projections lie beside it
  int sense = +1;                // -1: the sample turning against the file's statement
  void validate() const;
};

struct ImportRun {
  std::filesystem::path scan_file;
  ScanDescription scan;               // as read back from scan_file
  std::vector<std::string> notes;     // what was read from where (detector size, pixel map, NXtomo's numbers)
  std::vector<std::string> warnings;  // missing projection files, keys not modelled, the scan reader's own
  /// "wrote scan.json (225 views, detector 239 x 190) and scan.matrices.json"
  std::string brief() const;
  /// The notes, then the geometry summary (distances, magnification, cone angle, field of view,
  /// a voxel to start from).
  std::string report() const;
};

/// Each validates its request, then reads, checks and writes as above. Throws InputError naming
/// the file or request field and what was expected; nothing is written then.
ImportRun run_import(const CircularImportRequest& request);
ImportRun run_import(const ConeVecImportRequest& request);
ImportRun run_import(const RtkImportRequest& request);
ImportRun run_import(const MatricesImportRequest& request);
/// `progress` receives the frames copied out, of all.
ImportRun run_import(const NxTomoImportRequest& request, const std::function<void(int written, int total)>& progress = {});
ImportRun run_import(const NikonImportRequest& request);

}  // namespace ctk

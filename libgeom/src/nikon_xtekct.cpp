#include "ctk/geom/nikon_xtekct.hpp"

#include <algorithm>

#include <Eigen/Geometry>
#include <cmath>
#include <fstream>
#include <map>
#include <optional>

#include "ctk/core/error.hpp"
#include "ctk/core/file_names.hpp"
#include "ctk/geom/astra.hpp"

namespace ctk {

namespace fs = std::filesystem;

namespace {

std::string trimmed(const std::string& s) {
  const std::size_t a = s.find_first_not_of(" \t\r\n");
  if (a == std::string::npos) return {};
  return s.substr(a, s.find_last_not_of(" \t\r\n") - a + 1);
}

// `Key=Value` lines (sections and `;`/`#` remarks skipped); the first occurrence of a key holds.
class KeyValues {
 public:
  explicit KeyValues(const fs::path& file) : file_(file) {
    require_regular_file(file);
    std::ifstream in(file);
    if (!in) throw InputError(file.string(), "", "cannot be read");
    std::string line;
    int number = 0;
    while (std::getline(in, line)) {
      ++number;
      line = trimmed(line);
      if (line.empty() || line.front() == '[' || line.front() == ';' || line.front() == '#') continue;
      const std::size_t eq = line.find('=');
      if (eq == std::string::npos) continue;  // vendor files carry free text in some sections
      const std::string key = trimmed(line.substr(0, eq));
      if (!values_.count(key)) values_[key] = {trimmed(line.substr(eq + 1)), number};
    }
  }

  bool has(const std::string& key) const { return values_.count(key) > 0; }
  std::string text(const std::string& key) const { return has(key) ? values_.at(key).first : std::string(); }

  double number(const std::string& key) const {
    const std::optional<double> v = optional_number(key);
    if (!v) throw InputError(file_.string(), "key '" + key + "'", "missing");
    return *v;
  }
  std::optional<double> optional_number(const std::string& key) const {
    if (!has(key)) return std::nullopt;
    const auto& [text, line] = values_.at(key);
    std::size_t used = 0;
    double v = 0;
    try {
      v = std::stod(text, &used);
    } catch (const std::exception&) {
      used = 0;
    }
    if (used == 0 || trimmed(text.substr(used)) != "" || !std::isfinite(v))
      throw InputError(file_.string(), "key '" + key + "' (line " + std::to_string(line) + ")",
                       "expected a number, got '" + text + "'");
    return v;
  }
  int count(const std::string& key) const {
    const double v = number(key);
    if (!(v >= 1 && v <= 1e9) || v != std::floor(v))
      throw InputError(file_.string(), "key '" + key + "'", "expected a whole number above 0, got " + text(key));
    return static_cast<int>(v);
  }
  double positive(const std::string& key) const {
    const double v = number(key);
    if (!(v > 0)) throw InputError(file_.string(), "key '" + key + "'", "expected a number above 0, got " + text(key));
    return v;
  }
  // A length in mm no scanner has outside [1 um, 100 m] (a distance of 1e-300 made no projection).
  double length_mm(const std::string& key) const {
    const double v = positive(key);
    if (!(v >= 1e-3 && v <= 1e5))
      throw InputError(file_.string(), "key '" + key + "'", "expected a length between 0.001 and 100000 mm, got " + text(key));
    return v;
  }

 private:
  fs::path file_;
  std::map<std::string, std::pair<std::string, int>> values_;
};

Eigen::Matrix3d about(const Eigen::Vector3d& axis, double angle) { return Eigen::AngleAxisd(angle, axis).toRotationMatrix(); }

}  // namespace

NikonScan read_xtekct(const fs::path& file) {
  const KeyValues kv(file);
  NikonScan s;
  s.file = file;
  s.name = kv.text("Name");
  s.projections = kv.count("Projections");
  s.white_level = kv.positive("WhiteLevel");
  s.detector = Detector{kv.count("DetectorPixelsX"), kv.count("DetectorPixelsY"), kv.length_mm("DetectorPixelSizeX"),
                        kv.length_mm("DetectorPixelSizeY")};
  s.source_to_object_mm = kv.length_mm("SrcToObject");
  s.source_to_detector_mm = kv.length_mm("SrcToDetector");
  if (!(s.source_to_object_mm < s.source_to_detector_mm))
    throw InputError(file.string(), "key 'SrcToObject'",
                     kv.text("SrcToObject") + " mm is not less than SrcToDetector " + kv.text("SrcToDetector") + " mm");
  s.initial_angle_deg = kv.optional_number("InitialAngle").value_or(0.0);
  s.angular_step_deg = kv.number("AngularStep");
  const double top = kv.optional_number("CentreOfRotationTop").value_or(0.0);
  const double bottom = kv.optional_number("CentreOfRotationBottom").value_or(0.0);
  const double magnification_inverse = s.source_to_object_mm / s.source_to_detector_mm;
  s.axis_offset_mm = kv.optional_number("ObjectOffsetX").value_or(0.5 * (top + bottom) * magnification_inverse);
  if (const auto roll = kv.optional_number("ObjectRoll"))
    s.axis_roll_rad = *roll * M_PI / 180.0;
  else
    s.axis_roll_rad = -std::atan2(top - bottom, s.detector.rows * s.detector.pitch_v_mm);
  s.axis_tilt_rad = -kv.optional_number("ObjectTilt").value_or(0.0) * M_PI / 180.0;
  for (const char* key : {"DetectorOffsetX", "DetectorOffsetY"})
    if (kv.optional_number(key).value_or(0.0) != 0.0)
      s.warnings.push_back(
          std::string(key) + " = " + kv.text(key) +
          " mm is not modelled (the detector is taken centred on the beam); ctk refine measures the detector's offset");

  // InputFolderName is often a path on the acquisition PC: only a folder beside the file is used,
  // named relative to it and staying inside it (no root, no "..": a file must not send the import
  // to read another folder of the machine).
  const std::string input = kv.text("InputFolderName");
  const fs::path folder = file.parent_path();
  s.input_folder = folder;
  const fs::path named(input);
  const bool beside = !input.empty() && input.find_first_of(":\\") == std::string::npos && named.is_relative() &&
                      std::none_of(named.begin(), named.end(), [](const fs::path& part) { return part == ".."; });
  if (beside && fs::is_directory(folder / named)) {
    s.input_folder = folder / named;
  } else if (!input.empty() && !beside) {
    s.warnings.push_back("InputFolderName = " + input + " is not a folder beside " + file.filename().string() +
                         ": the projections are looked for beside the file");
  }
  return s;
}

std::vector<ProjectionMatrix> nikon_matrices(const NikonScan& s, int sense) {
  if (sense != 1 && sense != -1) throw std::invalid_argument("nikon_matrices: the sense must be +1 or -1");
  const Eigen::Vector3d source(0, 0, 0), axis_point(-s.axis_offset_mm, s.source_to_object_mm, 0),
      detector_centre(0, s.source_to_detector_mm, 0);
  // First pixel top right as seen from the source: columns run along -x, rows along -z.
  const Eigen::Vector3d column_step(-s.detector.pitch_u_mm, 0, 0), row_step(0, 0, -s.detector.pitch_v_mm);
  const Eigen::Matrix3d axis_frame =
      about(Eigen::Vector3d::UnitX(), s.axis_tilt_rad) * about(Eigen::Vector3d::UnitY(), s.axis_roll_rad);
  std::vector<ProjectionMatrix> out;
  for (int k = 0; k < s.projections; ++k) {
    const double angle = (180.0 - sense * (s.initial_angle_deg + k * s.angular_step_deg)) * M_PI / 180.0;
    // Sample (volume) to lab: X_lab = axis_point + axis_frame Rz(angle) X; lab to volume is its inverse.
    const Eigen::Matrix3d to_volume = (axis_frame * about(Eigen::Vector3d::UnitZ(), angle)).transpose();
    const Eigen::Vector3d src = to_volume * (source - axis_point), det = to_volume * (detector_centre - axis_point),
                          u = to_volume * column_step, v = to_volume * row_step;
    try {
      out.push_back(from_cone_vec(make_cone_vec(src, det, u, v), s.detector));
    } catch (const std::invalid_argument&) {
      throw InputError(s.file.string(), "projection " + std::to_string(k),
                       "its angle, distances, axis offset and pixel size describe no cone-beam projection (a number too large "
                       "or in the wrong unit?)");
    }
  }
  return out;
}

std::vector<fs::path> nikon_projection_files(const NikonScan& s) {
  std::vector<fs::path> files;
  for (const char* extension : {".tif", ".tiff"}) {
    files = matching_files(s.input_folder, s.name.empty() ? std::string("*") + extension : s.name + "_*" + extension);
    if (!files.empty()) break;
  }
  if (static_cast<int>(files.size()) != s.projections)
    throw InputError(s.file.string(), "key 'Projections'",
                     std::to_string(s.projections) + " projections, but " + s.input_folder.string() + " holds " +
                         std::to_string(files.size()) + " files named " +
                         (s.name.empty() ? std::string("*.tif") : s.name + "_*.tif"));
  return files;
}

}  // namespace ctk

#include "ctk/geom/rtk_geometry.hpp"

#include <strings.h>
#include <Eigen/Geometry>
#include <Eigen/LU>
#include <Eigen/SVD>
#include <algorithm>
#include <array>
#include <cmath>
#include <iomanip>
#include <pugixml.hpp>
#include <sstream>
#include <stdexcept>
#include <string>

#include "ctk/core/atomic_write.hpp"
#include "ctk/core/error.hpp"

namespace ctk {

namespace {

constexpr double degree = M_PI / 180.0;

Eigen::Matrix3d rotation_x(double a) { return Eigen::AngleAxisd(a, Eigen::Vector3d::UnitX()).toRotationMatrix(); }
Eigen::Matrix3d rotation_y(double a) { return Eigen::AngleAxisd(a, Eigen::Vector3d::UnitY()).toRotationMatrix(); }
Eigen::Matrix3d rotation_z(double a) { return Eigen::AngleAxisd(a, Eigen::Vector3d::UnitZ()).toRotationMatrix(); }

// Volume to RTK's rotated frame: ITK's Euler angles in Z-X-Y order of the negated angles.
Eigen::Matrix3d rtk_rotation(const RtkProjection& p) {
  return rotation_z(-p.in_plane_deg * degree) * rotation_x(-p.out_of_plane_deg * degree) * rotation_y(-p.gantry_deg * degree);
}

// Detector mm (x, y, 1) to ctk pixels (u, v, 1): centred, y along or against the rows.
Eigen::Matrix3d detector_mm_to_pixels(const Detector& d, RtkRows rows) {
  const Eigen::Vector2d c = d.centre_px();
  const double sense = rows == RtkRows::as_stored ? 1.0 : -1.0;
  Eigen::Matrix3d A;
  A << 1 / d.pitch_u_mm, 0, c.x(), 0, sense / d.pitch_v_mm, c.y(), 0, 0, 1;
  return A;
}

constexpr const char* rows_comment = "ctk pixel map: ";
constexpr const char* frame_comment = "ctk volume frame: RTK (x, y, z) = holder (x, z, -y)";

// Holder coordinates of a point given in RTK's volume frame of a ctk export.
Eigen::Matrix4d holder_from_rtk() {
  Eigen::Matrix4d H = Eigen::Matrix4d::Identity();
  H.block<3, 3>(0, 0) << 1, 0, 0, 0, 0, -1, 0, 1, 0;  // RTK x, y, z along holder x, z, -y
  return H;
}

// Angles in [0, 360), as RTK stores them.
double wrapped_degrees(double a) { return a - 360.0 * std::floor(a / 360.0); }

// Largest pixel distance between two matrices over points spread through the cone they share:
// rays through the detector's corners and centre, from a tenth to nine tenths of the way to it.
double largest_pixel_difference(const ProjectionMatrix& a, const ProjectionMatrix& b, const Detector& d) {
  // Points s + lambda M^-1 (u, v, 1) lie on the ray through (u, v) at depth lambda (mm).
  const Eigen::Vector3d s = a.source_position();
  const Eigen::Matrix3d M_inverse = a.matrix().leftCols<3>().inverse();
  const double sdd = std::abs(a.decompose().intrinsics.fu_px) * d.pitch_u_mm;
  double largest = 0;
  for (const Eigen::Vector2d& uv : {Eigen::Vector2d(0, 0), Eigen::Vector2d(d.cols - 1, 0), Eigen::Vector2d(0, d.rows - 1),
                                    Eigen::Vector2d(d.cols - 1, d.rows - 1), d.centre_px()})
    for (double f : {0.1, 0.5, 0.9}) {
      const Eigen::Vector3d X = s + f * sdd * M_inverse * Eigen::Vector3d(uv.x(), uv.y(), 1.0);
      largest = std::max(largest, (a.project(X) - b.project(X)).norm());
    }
  return largest;
}

}  // namespace

const char* to_string(RtkRows rows) { return rows == RtkRows::as_stored ? "as-stored" : "flipped"; }

RtkRows rtk_rows_from_string(const std::string& name) {
  if (name == "as-stored") return RtkRows::as_stored;
  if (name == "flipped") return RtkRows::flipped;
  throw std::invalid_argument("expected 'as-stored' or 'flipped', got '" + name + "'");
}

RtkRows rtk_rows_for(const ProjectionMatrix& P) {
  return P.decompose().intrinsics.fu_px < 0 ? RtkRows::as_stored : RtkRows::flipped;
}

Matrix34d rtk_matrix(const RtkProjection& p) {
  const double sid = p.source_to_isocentre_mm, sdd = p.source_to_detector_mm;
  const double sx = p.source_offset_x_mm, sy = p.source_offset_y_mm;
  Eigen::Matrix3d projection_translation = Eigen::Matrix3d::Identity();
  projection_translation(0, 2) = sx - p.projection_offset_x_mm;
  projection_translation(1, 2) = sy - p.projection_offset_y_mm;
  Matrix34d magnification = Matrix34d::Zero();
  magnification(0, 0) = -sdd;
  magnification(1, 1) = -sdd;
  magnification(2, 2) = 1;
  magnification(2, 3) = -sid;
  Eigen::Matrix4d source_translation = Eigen::Matrix4d::Identity();
  source_translation(0, 3) = -sx;
  source_translation(1, 3) = -sy;
  Eigen::Matrix4d rotation = Eigen::Matrix4d::Identity();
  rotation.topLeftCorner<3, 3>() = rtk_rotation(p);
  return projection_translation * magnification * source_translation * rotation;
}

ProjectionMatrix from_rtk(const RtkProjection& p, const Detector& detector, RtkRows rows) {
  if (!(p.source_to_detector_mm > 0))
    throw std::invalid_argument("the source-to-detector distance is not positive (a parallel or reversed projection)");
  // RTK's depth (z - sid) is negative in front of the source; ctk's is positive.
  return ProjectionMatrix(-(detector_mm_to_pixels(detector, rows) * rtk_matrix(p)));
}

RtkProjection to_rtk(const ProjectionMatrix& P, const Detector& detector, RtkRows rows) {
  const Matrix34d M = -(detector_mm_to_pixels(detector, rows).inverse() * P.matrix());
  // Third row [r3 | -sid] (P is normalised: r3 has unit norm); the first two rows are
  // -sdd r_i + a_i r3 with a_i = s_i - p_i (source minus projection offset) and constants
  // sdd s_i - a_i sid.
  const Eigen::Vector3d r3 = M.row(2).head<3>().transpose();
  const double sid = -M(2, 3);
  std::array<Eigen::Vector3d, 2> r;
  std::array<double, 2> a{}, scale{};
  for (int i = 0; i < 2; ++i) {
    const Eigen::Vector3d row = M.row(i).head<3>().transpose();
    a[static_cast<std::size_t>(i)] = row.dot(r3);
    const Eigen::Vector3d q = row - a[static_cast<std::size_t>(i)] * r3;
    scale[static_cast<std::size_t>(i)] = q.norm();
    r[static_cast<std::size_t>(i)] = -q / q.norm();
  }
  Eigen::Matrix3d R;
  R << r[0].transpose(), r[1].transpose(), r3.transpose();
  if (R.determinant() < 0)
    throw std::invalid_argument(std::string("the detector is mirrored under the pixel map ") + to_string(rows) +
                                ": its columns, rows and the beam make a left-handed frame there (the other map holds it)");
  // The nearest rotation; what it leaves (skew, unequal scales) is measured below.
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(R, Eigen::ComputeFullU | Eigen::ComputeFullV);
  R = svd.matrixU() * svd.matrixV().transpose();

  RtkProjection p;
  p.source_to_isocentre_mm = sid;
  p.source_to_detector_mm = 0.5 * (scale[0] + scale[1]);
  const double sdd = p.source_to_detector_mm;
  p.source_offset_x_mm = (M(0, 3) + a[0] * sid) / sdd;
  p.source_offset_y_mm = (M(1, 3) + a[1] * sid) / sdd;
  p.projection_offset_x_mm = p.source_offset_x_mm - a[0];
  p.projection_offset_y_mm = p.source_offset_y_mm - a[1];
  // R = Rz(c) Rx(a) Ry(b): R(2,1) = sin a, R(2,0) = -cos a sin b, R(2,2) = cos a cos b,
  // R(0,1) = -sin c cos a, R(1,1) = cos c cos a. At cos a = 0 only c -/+ b is fixed: b = 0.
  const double ax = std::asin(std::clamp(R(2, 1), -1.0, 1.0));
  double ay = 0, az = 0;
  if (std::abs(std::cos(ax)) > 1e-12) {
    ay = std::atan2(-R(2, 0), R(2, 2));
    az = std::atan2(-R(0, 1), R(1, 1));
  } else {
    az = std::atan2(R(1, 0), R(0, 0));
  }
  p.out_of_plane_deg = wrapped_degrees(-ax / degree);
  p.gantry_deg = wrapped_degrees(-ay / degree);
  p.in_plane_deg = wrapped_degrees(-az / degree);

  const double difference = largest_pixel_difference(P, from_rtk(p, detector, rows), detector);
  if (!(difference <= 1e-6)) {
    std::ostringstream message;
    message << "RTK's parameters hold this matrix only to " << difference
            << " px: its pixel grid is skewed or not square in mm (RTK has one source-to-detector distance for both axes)";
    throw std::invalid_argument(message.str());
  }
  return p;
}

namespace {

// The parameter elements, by RTK's names, and where each lives in RtkProjection.
struct Parameter {
  const char* name;
  double RtkProjection::*field;
};
constexpr std::array<Parameter, 10> parameters{{
    {"SourceToIsocenterDistance", &RtkProjection::source_to_isocentre_mm},
    {"SourceToDetectorDistance", &RtkProjection::source_to_detector_mm},
    {"GantryAngle", &RtkProjection::gantry_deg},
    {"Angle", &RtkProjection::gantry_deg},  // version 1's name, still read by RTK
    {"OutOfPlaneAngle", &RtkProjection::out_of_plane_deg},
    {"InPlaneAngle", &RtkProjection::in_plane_deg},
    {"SourceOffsetX", &RtkProjection::source_offset_x_mm},
    {"SourceOffsetY", &RtkProjection::source_offset_y_mm},
    {"ProjectionOffsetX", &RtkProjection::projection_offset_x_mm},
    {"ProjectionOffsetY", &RtkProjection::projection_offset_y_mm},
}};

double number(const std::string& file, const std::string& where, const char* text) {
  std::istringstream in(text);
  in.imbue(std::locale::classic());
  double x = 0;
  std::string rest;
  if (!(in >> x) || (in >> rest) || !std::isfinite(x))
    throw InputError(file, where, std::string("expected one finite number, got '") + text + "'");
  return x;
}

class Reader {
 public:
  explicit Reader(std::string file) : file_(std::move(file)) {}

  // Applies a parameter element to the running values; true if `e` was one.
  bool parameter(const pugi::xml_node& e, const std::string& where) {
    if (strcasecmp(e.name(), "RadiusCylindricalDetector") == 0) {
      if (number(file_, where, e.child_value()) != 0)
        throw InputError(file_, where, "a cylindrical detector; ctk's detectors are flat");
      return true;
    }
    for (const Parameter& p : parameters)
      if (strcasecmp(e.name(), p.name) == 0) {
        current_.*p.field = number(file_, where, e.child_value());
        if (p.field == &RtkProjection::source_to_isocentre_mm) has_sid_ = true;
        if (p.field == &RtkProjection::source_to_detector_mm) has_sdd_ = true;
        return true;
      }
    return false;
  }

  RtkProjection projection(const pugi::xml_node& node, const std::string& where) {
    pugi::xml_node matrix;
    for (const pugi::xml_node& e : node.children()) {
      if (e.type() != pugi::node_element) continue;
      if (strcasecmp(e.name(), "Matrix") == 0) {
        matrix = e;
      } else {
        parameter(e, where + "." + e.name());  // collimation and other elements do not change the geometry
      }
    }
    if (!has_sid_) throw InputError(file_, where, "no SourceToIsocenterDistance before or in it");
    if (!has_sdd_) throw InputError(file_, where, "no SourceToDetectorDistance before or in it");
    if (!(current_.source_to_detector_mm > 0))
      throw InputError(file_, where + ".SourceToDetectorDistance",
                       "not positive: a parallel projection, which ctk's cone-beam matrices cannot describe");
    if (matrix) check_matrix(matrix, where + ".Matrix");
    return current_;
  }

 private:
  // RTK refuses a file whose matrix disagrees with its parameters; so does ctk, relative to the
  // matrix's scale (the source-to-detector distance) rather than RTK's absolute 0.001.
  void check_matrix(const pugi::xml_node& e, const std::string& where) const {
    std::istringstream in(e.child_value());
    in.imbue(std::locale::classic());
    Matrix34d stored;
    for (int i = 0; i < 12; ++i)
      if (!(in >> stored(i / 4, i % 4)) || !std::isfinite(stored(i / 4, i % 4)))
        throw InputError(file_, where, "expected 12 finite numbers (3 rows of 4)");
    std::string rest;
    if (in >> rest) throw InputError(file_, where, "more than 12 numbers");
    const Matrix34d computed = rtk_matrix(current_);
    const double tolerance = 1e-9 * std::max(1.0, computed.cwiseAbs().maxCoeff());
    const double difference = (stored - computed).cwiseAbs().maxCoeff();
    if (difference > std::max(tolerance, 1e-6)) {
      std::ostringstream message;
      message << "disagrees with the projection's parameters by up to " << difference << " (RTK would refuse the file too)";
      throw InputError(file_, where, message.str());
    }
  }

  std::string file_;
  RtkProjection current_;
  bool has_sid_ = false, has_sdd_ = false;
};

}  // namespace

RtkGeometry read_rtk_geometry(const std::filesystem::path& file) {
  require_regular_file(file);
  pugi::xml_document document;
  const pugi::xml_parse_result parsed = document.load_file(file.c_str(), pugi::parse_default | pugi::parse_comments);
  if (!parsed)
    throw InputError(file.string(), "byte " + std::to_string(parsed.offset), std::string("not XML: ") + parsed.description());
  const pugi::xml_node root = document.document_element();
  if (strcasecmp(root.name(), "RTKThreeDCircularGeometry") != 0)
    throw InputError(file.string(), std::string("<") + root.name() + ">",
                     "expected the root element <RTKThreeDCircularGeometry> of an RTK geometry file");
  const pugi::xml_attribute version = root.attribute("version");
  if (version && version.as_int() != 2 && version.as_int() != 3)
    throw InputError(file.string(), "version", std::string("version ") + version.value() + "; ctk reads versions 2 and 3");
  Reader reader(file.string());
  RtkGeometry g;
  for (const pugi::xml_node& e : root.children()) {
    if (e.type() == pugi::node_comment) {
      const std::string text = e.value();
      const std::size_t at = text.find(rows_comment);
      if (at != std::string::npos) {
        const std::string rest = text.substr(at + std::string(rows_comment).size());
        g.rows = rest.rfind("as-stored", 0) == 0 ? RtkRows::as_stored : RtkRows::flipped;
      }
      if (text.find(frame_comment) != std::string::npos) g.holder_z_on_rtk_y = true;
    }
    if (e.type() != pugi::node_element) continue;
    if (strcasecmp(e.name(), "Projection") == 0)
      g.views.push_back(reader.projection(e, "Projection[" + std::to_string(g.views.size()) + "]"));
    else
      reader.parameter(e, e.name());
  }
  if (g.views.empty()) throw InputError(file.string(), "", "no <Projection> element");
  return g;
}

ProjectionMatrix holder_matrix_in_rtk_frame(const ProjectionMatrix& P) {
  return ProjectionMatrix(Matrix34d(P.matrix() * holder_from_rtk()));
}

ProjectionMatrix rtk_frame_matrix_in_holder(const ProjectionMatrix& P) {
  return ProjectionMatrix(Matrix34d(P.matrix() * holder_from_rtk().inverse()));
}

std::vector<ProjectionMatrix> holder_matrices(const RtkGeometry& g, const Detector& detector, RtkRows rows) {
  std::vector<ProjectionMatrix> out;
  out.reserve(g.views.size());
  for (const RtkProjection& v : g.views) {
    const ProjectionMatrix P = from_rtk(v, detector, rows);
    out.push_back(g.holder_z_on_rtk_y ? rtk_frame_matrix_in_holder(P) : P);
  }
  return out;
}

void write_rtk_geometry(const std::vector<RtkProjection>& views, RtkRows rows, const std::filesystem::path& file,
                        bool holder_z_on_rtk_y) {
  if (views.empty()) throw std::invalid_argument("write_rtk_geometry: no views");
  write_file_atomically(file, [&](std::ostream& out) {
    out.imbue(std::locale::classic());
    out << std::setprecision(17);
    out << "<?xml version=\"1.0\"?>\n<!DOCTYPE RTKGEOMETRY>\n<RTKThreeDCircularGeometry version=\"3\">\n";
    out << "  <!-- " << rows_comment << to_string(rows) << ": detector x = (u - (cols - 1) / 2) pitch_u, y = "
        << (rows == RtkRows::as_stored ? "(v - (rows - 1) / 2)" : "((rows - 1) / 2 - v)")
        << " pitch_v in mm, (u, v) = (column, row) of the stored images -->\n";
    if (holder_z_on_rtk_y)
      out << "  <!-- " << frame_comment << ": the holder's axis is RTK's y, about which rtkfdk reconstructs -->\n";
    // A parameter equal over all views is written once (and not at all where it is RTK's default 0).
    std::vector<const Parameter*> per_view;
    for (const Parameter& p : parameters) {
      if (std::string(p.name) == "Angle") continue;
      const double first = views.front().*p.field;
      const bool constant = std::all_of(views.begin(), views.end(), [&](const RtkProjection& v) { return v.*p.field == first; });
      const bool distance = p.field == &RtkProjection::source_to_isocentre_mm || p.field == &RtkProjection::source_to_detector_mm;
      if (constant && p.field != &RtkProjection::gantry_deg) {
        if (first != 0 || distance) out << "  <" << p.name << ">" << first << "</" << p.name << ">\n";
      } else {
        per_view.push_back(&p);
      }
    }
    for (const RtkProjection& v : views) {
      out << "  <Projection>\n";
      for (const Parameter* p : per_view) out << "    <" << p->name << ">" << v.*(p->field) << "</" << p->name << ">\n";
      const Matrix34d M = rtk_matrix(v);
      out << "    <Matrix>\n";
      for (int r = 0; r < 3; ++r) out << "      " << M(r, 0) << " " << M(r, 1) << " " << M(r, 2) << " " << M(r, 3) << "\n";
      out << "    </Matrix>\n  </Projection>\n";
    }
    out << "</RTKThreeDCircularGeometry>\n";
  });
}

}  // namespace ctk

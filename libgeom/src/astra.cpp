#include "ctk/geom/astra.hpp"

#include <Eigen/LU>
#include <fstream>
#include <sstream>

#include "ctk/core/atomic_write.hpp"
#include "ctk/core/error.hpp"

namespace ctk {

ConeVec to_cone_vec(const ProjectionMatrix& P, const Detector& detector, double mm_per_unit) {
  const Eigen::Matrix3d Minv = P.matrix().leftCols<3>().inverse();
  const Eigen::Vector3d s = P.source_position();
  // Points s + lambda * Minv (u, v, 1) have depth lambda: lambda > 0 puts the plane in front.
  const double lambda = detector.pitch_u_mm / Minv.col(0).norm();
  const Eigen::Vector2d c = detector.centre_px();
  const Eigen::Vector3d d = s + lambda * Minv * Eigen::Vector3d(c.x(), c.y(), 1.0);
  const Eigen::Vector3d u = lambda * Minv.col(0), v = lambda * Minv.col(1);
  return make_cone_vec(s, d, u, v, mm_per_unit);
}

ConeVec make_cone_vec(const Eigen::Vector3d& source, const Eigen::Vector3d& detector_centre, const Eigen::Vector3d& u,
                      const Eigen::Vector3d& v, double mm_per_unit) {
  ConeVec out{};
  const Eigen::Vector3d* parts[4] = {&source, &detector_centre, &u, &v};
  for (std::size_t p = 0; p < 4; ++p)
    for (Eigen::Index i = 0; i < 3; ++i) out[3 * p + static_cast<std::size_t>(i)] = (*parts[p])[i] / mm_per_unit;
  return out;
}

ProjectionMatrix from_cone_vec(const ConeVec& vec, const Detector& detector, double mm_per_unit) {
  auto at = [&](std::size_t i) -> Eigen::Vector3d { return Eigen::Vector3d(vec[i], vec[i + 1], vec[i + 2]) * mm_per_unit; };
  const Eigen::Vector3d s = at(0), d = at(3), u = at(6), v = at(9);
  const Eigen::Vector2d c = detector.centre_px();
  const Eigen::Vector3d o = d - c.x() * u - c.y() * v;  // centre of pixel (0, 0)
  Eigen::Matrix3d B;
  B << u, v, o - s;
  Matrix34d P;
  P.leftCols<3>() = B.inverse();
  P.col(3) = -B.inverse() * s;
  return ProjectionMatrix(P).oriented_towards(d);
}

std::vector<ConeVec> read_cone_vecs(const std::filesystem::path& file) {
  require_regular_file(file);
  std::ifstream in(file);
  if (!in) throw InputError(file.string(), "", "cannot open the cone_vec file");
  std::vector<ConeVec> out;
  std::string line;
  int line_number = 0;
  while (std::getline(in, line)) {
    ++line_number;
    if (line.find_first_not_of(" \t\r") == std::string::npos) continue;
    std::istringstream ss(line);
    ConeVec v{};
    for (auto& x : v) {
      if (!(ss >> x) || !std::isfinite(x))
        throw InputError(file.string(), "line " + std::to_string(line_number), "expected 12 finite numbers");
    }
    double extra;
    if (ss >> extra) throw InputError(file.string(), "line " + std::to_string(line_number), "more than 12 numbers");
    out.push_back(v);
  }
  if (out.empty()) throw InputError(file.string(), "", "no rows of 12 numbers (an empty cone_vec file)");
  return out;
}

void write_cone_vecs(const std::vector<ConeVec>& vecs, const std::filesystem::path& file) {
  write_file_atomically(file, [&](std::ostream& out) {
    out.precision(17);
    for (const auto& v : vecs) {
      for (std::size_t i = 0; i < v.size(); ++i) out << (i ? " " : "") << v[i];
      out << '\n';
    }
  });
}

}  // namespace ctk

#include "ctk/phantoms/triangle_mesh.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <map>
#include <sstream>

#include "ctk/core/error.hpp"

namespace ctk {

namespace fs = std::filesystem;

namespace {

constexpr int kLeafTriangles = 4;

// Binary STL: an 80-byte header, a little-endian count, 50 bytes per triangle (normal, three
// vertices as float32, an attribute word). A file of exactly that size is binary; else ASCII.
bool read_binary(const std::string& bytes, std::vector<Eigen::Vector3d>& corners) {
  if (bytes.size() < 84) return false;
  std::uint32_t n = 0;
  std::memcpy(&n, bytes.data() + 80, 4);
  if (bytes.size() != 84 + 50 * static_cast<std::size_t>(n)) return false;
  for (std::uint32_t t = 0; t < n; ++t)
    for (int k = 0; k < 3; ++k) {
      float xyz[3];
      std::memcpy(xyz, bytes.data() + 84 + 50 * static_cast<std::size_t>(t) + 12 + 12 * static_cast<std::size_t>(k), 12);
      corners.emplace_back(xyz[0], xyz[1], xyz[2]);
    }
  return true;
}

void read_ascii(const std::string& text, const std::string& file, std::vector<Eigen::Vector3d>& corners) {
  std::istringstream in(text);
  std::string word;
  in >> word;
  if (word != "solid") throw InputError(file, "", "is neither a binary STL (84 + 50 n bytes) nor an ASCII one ('solid ...')");
  while (in >> word) {
    if (word != "vertex") continue;
    Eigen::Vector3d v;
    if (!(in >> v.x() >> v.y() >> v.z())) throw InputError(file, "", "a 'vertex' without three numbers");
    corners.push_back(v);
  }
  if (corners.size() % 3 != 0) throw InputError(file, "", "vertices that do not make whole triangles");
}

// Slab test: the ray's interval inside the box meets [0, infinity).
bool meets(const Eigen::AlignedBox3d& box, const Eigen::Vector3d& origin, const Eigen::Vector3d& inverse) {
  double t0 = 0, t1 = std::numeric_limits<double>::infinity();
  for (int a = 0; a < 3; ++a) {
    double near = (box.min()[a] - origin[a]) * inverse[a], far = (box.max()[a] - origin[a]) * inverse[a];
    if (std::isnan(near) || std::isnan(far)) {  // parallel to the slab, on its plane: inside when within it
      if (origin[a] < box.min()[a] || origin[a] > box.max()[a]) return false;
      continue;
    }
    if (near > far) std::swap(near, far);
    t0 = std::max(t0, near);
    t1 = std::min(t1, far);
    if (t0 > t1) return false;
  }
  return true;
}

}  // namespace

TriangleMesh TriangleMesh::read_stl(const fs::path& file, double scale_mm) {
  if (!(scale_mm > 0) || !std::isfinite(scale_mm)) throw InputError(file.string(), "scale_mm", "expected a positive unit in mm");
  std::error_code ec;
  if (!fs::is_regular_file(file, ec)) throw InputError(file.string(), "", "does not exist or is not a file");
  std::ifstream in(file, std::ios::binary);
  if (!in) throw InputError(file.string(), "", "cannot be read");
  std::ostringstream buffer;
  buffer << in.rdbuf();
  const std::string bytes = buffer.str();
  std::vector<Eigen::Vector3d> corners;
  if (!read_binary(bytes, corners)) read_ascii(bytes, file.string(), corners);
  if (corners.empty()) throw InputError(file.string(), "", "holds no triangle");
  // Shared corners become one vertex (exactly equal coordinates, as CAD exports write them).
  std::map<std::array<double, 3>, int> index;
  std::vector<Eigen::Vector3d> vertices;
  std::vector<std::array<int, 3>> triangles;
  for (std::size_t i = 0; i < corners.size(); i += 3) {
    std::array<int, 3> t{};
    for (int k = 0; k < 3; ++k) {
      const Eigen::Vector3d& c = corners[i + static_cast<std::size_t>(k)];
      if (!c.allFinite()) throw InputError(file.string(), "", "a vertex that is not a finite number");
      const auto [it, added] = index.try_emplace({c.x(), c.y(), c.z()}, static_cast<int>(vertices.size()));
      if (added) vertices.push_back(scale_mm * c);
      t[static_cast<std::size_t>(k)] = it->second;
    }
    if (t[0] != t[1] && t[1] != t[2] && t[0] != t[2]) triangles.push_back(t);  // degenerate ones add nothing
  }
  return TriangleMesh(std::move(vertices), std::move(triangles), file.string());
}

TriangleMesh::TriangleMesh(std::vector<Eigen::Vector3d> vertices, std::vector<std::array<int, 3>> triangles, std::string source)
    : vertices_(std::move(vertices)), triangles_(std::move(triangles)), source_(std::move(source)) {
  if (triangles_.size() < 4) throw InputError(source_, "", "a closed solid needs at least 4 triangles");
  // Closed and consistently wound: every directed edge once, and its reverse once.
  std::map<std::pair<int, int>, int> edges;
  for (const auto& t : triangles_)
    for (int k = 0; k < 3; ++k) ++edges[{t[static_cast<std::size_t>(k)], t[static_cast<std::size_t>((k + 1) % 3)]}];
  for (const auto& [edge, count] : edges) {
    const auto reverse = edges.find({edge.second, edge.first});
    if (count != 1 || reverse == edges.end() || reverse->second != 1)
      throw InputError(source_, "",
                       "is not a closed, consistently wound surface (an edge between vertices " + std::to_string(edge.first) +
                           " and " + std::to_string(edge.second) +
                           " is not shared by exactly two triangles wound opposite ways)");
  }
  if (volume_mm3() < 0)
    for (auto& t : triangles_) std::swap(t[1], t[2]);  // inside out: the normals made to point out
  order_.resize(triangles_.size());
  for (std::size_t i = 0; i < order_.size(); ++i) order_[i] = static_cast<int>(i);
  std::vector<Eigen::Vector3d> centroids;
  centroids.reserve(triangles_.size());
  for (const auto& t : triangles_)
    centroids.push_back((vertices_[static_cast<std::size_t>(t[0])] + vertices_[static_cast<std::size_t>(t[1])] +
                         vertices_[static_cast<std::size_t>(t[2])]) /
                        3);
  nodes_.reserve(2 * triangles_.size() / kLeafTriangles + 1);
  build(0, static_cast<int>(triangles_.size()), centroids);
}

double TriangleMesh::volume_mm3() const {
  double six = 0;
  for (const auto& t : triangles_)
    six += vertices_[static_cast<std::size_t>(t[0])].dot(
        vertices_[static_cast<std::size_t>(t[1])].cross(vertices_[static_cast<std::size_t>(t[2])]));
  return six / 6;
}

int TriangleMesh::build(int first, int count, std::vector<Eigen::Vector3d>& centroids) {
  const int at = static_cast<int>(nodes_.size());
  nodes_.emplace_back();
  Eigen::AlignedBox3d box, centres;
  for (int i = first; i < first + count; ++i) {
    const auto& t = triangles_[static_cast<std::size_t>(order_[static_cast<std::size_t>(i)])];
    for (int k : t) box.extend(vertices_[static_cast<std::size_t>(k)]);
    centres.extend(centroids[static_cast<std::size_t>(order_[static_cast<std::size_t>(i)])]);
  }
  nodes_[static_cast<std::size_t>(at)].box = box;
  if (count <= kLeafTriangles) {
    nodes_[static_cast<std::size_t>(at)].first = first;
    nodes_[static_cast<std::size_t>(at)].count = count;
    return at;
  }
  // Split at the median of the triangles' centroids along the box's longest side.
  int axis = 0;
  centres.sizes().maxCoeff(&axis);
  const auto begin = order_.begin() + first, middle = begin + count / 2, end = begin + count;
  std::nth_element(begin, middle, end, [&](int a, int b) {
    return centroids[static_cast<std::size_t>(a)][axis] < centroids[static_cast<std::size_t>(b)][axis];
  });
  const int left = build(first, count / 2, centroids);
  const int right = build(first + count / 2, count - count / 2, centroids);
  nodes_[static_cast<std::size_t>(at)].left = left;
  nodes_[static_cast<std::size_t>(at)].right = right;
  return at;
}

template <typename Hit>
void TriangleMesh::crossings(const Eigen::Vector3d& origin, const Eigen::Vector3d& direction, Hit&& hit) const {
  const Eigen::Vector3d inverse = direction.cwiseInverse();
  int stack[128];
  int size = 0;
  stack[size++] = 0;
  while (size > 0) {
    const Node& node = nodes_[static_cast<std::size_t>(stack[--size])];
    if (!meets(node.box, origin, inverse)) continue;
    if (node.count == 0) {
      stack[size++] = node.left;
      stack[size++] = node.right;
      continue;
    }
    for (int i = node.first; i < node.first + node.count; ++i) {
      // Moller-Trumbore; a ray along the triangle's plane does not cross it.
      const auto& t = triangles_[static_cast<std::size_t>(order_[static_cast<std::size_t>(i)])];
      const Eigen::Vector3d& a = vertices_[static_cast<std::size_t>(t[0])];
      const Eigen::Vector3d e1 = vertices_[static_cast<std::size_t>(t[1])] - a,
                            e2 = vertices_[static_cast<std::size_t>(t[2])] - a;
      const Eigen::Vector3d p = direction.cross(e2);
      const double det = e1.dot(p);
      if (det == 0) continue;
      const double inv = 1 / det;
      const Eigen::Vector3d s = origin - a;
      const double u = s.dot(p) * inv;
      if (u < 0 || u > 1) continue;
      const Eigen::Vector3d q = s.cross(e1);
      const double v = direction.dot(q) * inv;
      if (v < 0 || u + v > 1) continue;
      const double distance = e2.dot(q) * inv;
      if (distance >= 0) hit(distance, det < 0);  // the outward normal e1 x e2 along the ray: leaving
    }
  }
}

std::vector<std::pair<double, bool>> TriangleMesh::surface_crossings(const Eigen::Vector3d& origin,
                                                                     const Eigen::Vector3d& direction) const {
  std::vector<std::pair<double, bool>> hits;
  crossings(origin, direction, [&](double t, bool leaving) { hits.emplace_back(t, leaving); });
  // A ray through an edge or a vertex crosses every triangle that shares it at the same t: one
  // crossing of the surface, counted once (crossings out and in at one t, a graze, both kept).
  std::sort(hits.begin(), hits.end());
  const double tolerance = 1e-9 * std::max(1.0, bounds().sizes().maxCoeff());
  std::vector<std::pair<double, bool>> once;
  for (const auto& h : hits)
    if (once.empty() || h.first - once.back().first > tolerance || h.second != once.back().second) once.push_back(h);
  return once;
}

double TriangleMesh::chord_mm(const Eigen::Vector3d& origin, const Eigen::Vector3d& direction) const {
  double length = 0;
  for (const auto& [t, leaving] : surface_crossings(origin, direction)) length += leaving ? t : -t;
  return std::max(0.0, length);
}

bool TriangleMesh::contains(const Eigen::Vector3d& point) const {
  if (!bounds().contains(point)) return false;
  int balance = 0;  // leaving minus entering along the ray: 1 from inside, 0 from outside
  for (const auto& crossing : surface_crossings(point, Eigen::Vector3d(0.5773, 0.5774, 0.5773).normalized()))
    balance += crossing.second ? 1 : -1;
  return balance > 0;
}

}  // namespace ctk

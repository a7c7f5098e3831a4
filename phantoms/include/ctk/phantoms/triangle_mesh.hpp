#pragma once
// A lab's own part from its CAD mesh (STL, binary or ASCII) as a phantom primitive: a closed,
// consistently wound triangle mesh whose chords are exact. Along a ray, every crossing of the
// surface at t >= 0 adds t where the ray leaves the solid and subtracts it where it enters
// (the side told by the triangle's winding), which sums to the length inside for any closed
// mesh, the ray's start inside or out. A bounding-volume hierarchy over the triangles keeps a
// ray's cost near the logarithm of their number.
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
#include <filesystem>
#include <string>
#include <utility>
#include <vector>

namespace ctk {

class TriangleMesh {
 public:
  /// Reads an STL file (binary, or ASCII `solid ... facet ... vertex x y z ...`), coordinates
  /// times `scale_mm` (the file's unit in mm). InputError naming the file when it cannot be read,
  /// is not STL, or is not closed (every edge shared by exactly two triangles, wound opposite
  /// ways); wound inside out, it is turned.
  static TriangleMesh read_stl(const std::filesystem::path& file, double scale_mm = 1.0);
  /// From vertices and triangles (indices), checked as read_stl checks a file; `source` names it.
  TriangleMesh(std::vector<Eigen::Vector3d> vertices, std::vector<std::array<int, 3>> triangles, std::string source);

  /// Length (mm) inside the solid of origin + t direction, t >= 0 (unit direction, mesh frame).
  double chord_mm(const Eigen::Vector3d& origin, const Eigen::Vector3d& direction) const;
  /// Inside the solid (crossings of a ray from the point counted).
  bool contains(const Eigen::Vector3d& point) const;
  const Eigen::AlignedBox3d& bounds() const { return nodes_.front().box; }
  std::size_t triangle_count() const { return triangles_.size(); }
  double volume_mm3() const;
  const std::string& source() const { return source_; }

 private:
  struct Node {
    Eigen::AlignedBox3d box;
    int first = 0, count = 0;  // a leaf's triangles (in order_), count 0 for an inner node
    int left = -1, right = -1;
  };
  int build(int first, int count, std::vector<Eigen::Vector3d>& centroids);
  /// Every crossing of the surface at t >= 0 (t, leaving), in order, each once.
  std::vector<std::pair<double, bool>> surface_crossings(const Eigen::Vector3d& origin, const Eigen::Vector3d& direction) const;
  /// Calls hit(t, leaving) for every triangle crossed at t >= 0.
  template <typename Hit>
  void crossings(const Eigen::Vector3d& origin, const Eigen::Vector3d& direction, Hit&& hit) const;

  std::vector<Eigen::Vector3d> vertices_;
  std::vector<std::array<int, 3>> triangles_;
  std::vector<int> order_;
  std::vector<Node> nodes_;
  std::string source_;
};

}  // namespace ctk

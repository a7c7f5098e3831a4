#include "ctk/plan/edge_tangency.hpp"

#include <cmath>
#include <stdexcept>

#include "ctk/core/error.hpp"
#include "ctk/geom/trajectory.hpp"

namespace ctk {

void EdgeTangencyOptions::validate() const {
  require_option(tangent_width_deg > 0 && tangent_width_deg < 90, "EdgeTangencyOptions.tangent_width_deg",
                 "an angle in (0, 90) deg", tangent_width_deg);
  require_option(normal_nside >= 1, "EdgeTangencyOptions.normal_nside", "a HEALPix nside of at least 1", normal_nside);
}

std::vector<double> tangent_edge_demand(const Volume& x, const SampleRegion& region,
                                        const std::vector<Eigen::Vector3d>& directions, const EdgeTangencyOptions& options) {
  options.validate();
  const HealpixSphere sphere(options.normal_nside);
  // Squared gradient per normal direction; a normal and its opposite are the same edge.
  std::vector<double> binned(static_cast<std::size_t>(sphere.size()), 0.0);
  const auto& n = x.layout.size;
  const Eigen::Vector3d half_step = (2.0 * x.layout.voxel_mm).cwiseInverse();
  for (int k = 1; k + 1 < n[2]; ++k)
    for (int j = 1; j + 1 < n[1]; ++j)
      for (int i = 1; i + 1 < n[0]; ++i) {
        if (!region.contains(x.layout.centre_of(i, j, k))) continue;
        const Eigen::Vector3d g((x.at(i + 1, j, k) - x.at(i - 1, j, k)) * half_step.x(),
                                (x.at(i, j + 1, k) - x.at(i, j - 1, k)) * half_step.y(),
                                (x.at(i, j, k + 1) - x.at(i, j, k - 1)) * half_step.z());
        const double g2 = g.squaredNorm();
        if (g2 > 0) binned[static_cast<std::size_t>(sphere.cell_of(g))] += g2;
      }
  const std::vector<Eigen::Vector3d> normals = sphere.directions();
  const double inv_sin_w = 1.0 / std::sin(options.tangent_width_deg * M_PI / 180.0);
  std::vector<double> demand(directions.size(), 0.0);
  double total = 0;
  for (std::size_t d = 0; d < directions.size(); ++d) {
    const Eigen::Vector3d u = directions[d].normalized();
    for (std::size_t c = 0; c < binned.size(); ++c) {
      if (binned[c] == 0) continue;
      const double t = normals[c].dot(u) * inv_sin_w;
      demand[d] += binned[c] * std::exp(-t * t);
    }
    total += demand[d];
  }
  if (!(total > 0)) return std::vector<double>(directions.size(), 1.0);
  const double mean = total / static_cast<double>(directions.size());
  for (double& v : demand) v /= mean;
  return demand;
}

}  // namespace ctk

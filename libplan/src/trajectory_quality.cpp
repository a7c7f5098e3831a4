#include "ctk/plan/trajectory_quality.hpp"

#include <Eigen/Dense>
#include <cmath>
#include <stdexcept>

namespace ctk {

std::array<int, 3> centre_of_mass_voxel(const Volume& truth, const SampleRegion& region) {
  const auto& n = truth.layout.size;
  Eigen::Vector3d sum(0, 0, 0);
  double mass = 0;
  for (int k = 0; k < n[2]; ++k)
    for (int j = 0; j < n[1]; ++j)
      for (int i = 0; i < n[0]; ++i)
        if (truth.at(i, j, k) > 0 && region.contains(truth.layout.centre_of(i, j, k))) {
          sum += truth.at(i, j, k) * Eigen::Vector3d(i, j, k);
          mass += truth.at(i, j, k);
        }
  if (!(mass > 0)) return {n[0] / 2, n[1] / 2, n[2] / 2};
  return {static_cast<int>(std::lround(sum.x() / mass)), static_cast<int>(std::lround(sum.y() / mass)),
          static_cast<int>(std::lround(sum.z() / mass))};
}

namespace {

// The RMSE over the region, and over its voxels away from the absorbers.
void add_rmse(const Volume& x, const Volume& truth, const SampleRegion& region, float absorber_above_per_mm,
              TrajectoryQuality& q) {
  const auto& n = x.layout.size;
  // An absorber voxel, or a face neighbour of one (partial volume, the absorber's own blur).
  auto near_absorber = [&](int i, int j, int k) {
    const int step[7][3] = {{0, 0, 0}, {1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
    for (const auto& s : step) {
      const int a = i + s[0], b = j + s[1], c = k + s[2];
      if (a >= 0 && b >= 0 && c >= 0 && a < n[0] && b < n[1] && c < n[2] && truth.at(a, b, c) > absorber_above_per_mm)
        return true;
    }
    return false;
  };
  double sum2 = 0, outside_sum2 = 0;
  std::size_t count = 0, outside = 0;
  for (int k = 0; k < n[2]; ++k)
    for (int j = 0; j < n[1]; ++j)
      for (int i = 0; i < n[0]; ++i)
        if (region.contains(x.layout.centre_of(i, j, k))) {
          const double d = x.at(i, j, k) - truth.at(i, j, k);
          sum2 += d * d;
          ++count;
          if (!near_absorber(i, j, k)) {
            outside_sum2 += d * d;
            ++outside;
          }
        }
  q.rmse_per_mm = count ? std::sqrt(sum2 / static_cast<double>(count)) : 0.0;
  q.rmse_outside_absorbers_per_mm = outside ? std::sqrt(outside_sum2 / static_cast<double>(outside)) : 0.0;
}

// Every pair of neighbouring voxels in the region across which the truth changes: the mean
// gradient there, per axis and over all.
void add_edge_gradients(const Volume& x, const Volume& truth, const SampleRegion& region, TrajectoryQuality& q) {
  const auto& n = x.layout.size;
  double all_gradient = 0, all_truth = 0;
  std::size_t edges = 0;
  for (int axis = 0; axis < 3; ++axis) {
    const int di = axis == 0, dj = axis == 1, dk = axis == 2;
    double along = 0;
    std::size_t along_edges = 0;
    for (int k = dk; k < n[2]; ++k)
      for (int j = dj; j < n[1]; ++j)
        for (int i = di; i < n[0]; ++i) {
          const float t0 = truth.at(i - di, j - dj, k - dk), t1 = truth.at(i, j, k);
          if (std::abs(t1 - t0) < 1e-6f) continue;
          if (!region.contains(x.layout.centre_of(i, j, k)) || !region.contains(x.layout.centre_of(i - di, j - dj, k - dk)))
            continue;
          const double g = std::abs(x.at(i, j, k) - x.at(i - di, j - dj, k - dk)) / x.layout.voxel_mm[axis];
          all_gradient += g;
          along += g;
          all_truth += std::abs(t1 - t0) / x.layout.voxel_mm[axis];
          ++edges;
          ++along_edges;
        }
    if (along_edges) q.edge_gradient_along_per_mm2[static_cast<std::size_t>(axis)] = along / static_cast<double>(along_edges);
  }
  if (edges) {
    q.edge_gradient_per_mm2 = all_gradient / static_cast<double>(edges);
    q.truth_edge_gradient_per_mm2 = all_truth / static_cast<double>(edges);
  }
}

// The line profiles through `through` along each axis, and their mean gradient where the truth
// has an edge.
void add_line_profiles(const Volume& x, const Volume& truth, const SampleRegion& region, const std::array<int, 3>& through,
                       TrajectoryQuality& q) {
  const auto& n = x.layout.size;
  double gradient = 0, truth_gradient = 0;
  std::size_t steps = 0;
  for (int axis = 0; axis < 3; ++axis) {
    LineProfile p{axis, through, {}, {}};
    std::array<int, 3> v = through;
    for (v[axis] = 0; v[axis] < n[axis]; ++v[axis]) {
      if (!region.contains(x.layout.centre_of(v[0], v[1], v[2]))) continue;
      p.reconstruction.push_back(x.at(v[0], v[1], v[2]));
      p.truth.push_back(truth.at(v[0], v[1], v[2]));
    }
    // Only where the truth has an edge: between edges a gradient is noise or streaks.
    for (std::size_t s = 1; s < p.reconstruction.size(); ++s) {
      if (std::abs(p.truth[s] - p.truth[s - 1]) < 1e-6f) continue;
      gradient += std::abs(p.reconstruction[s] - p.reconstruction[s - 1]) / x.layout.voxel_mm[axis];
      truth_gradient += std::abs(p.truth[s] - p.truth[s - 1]) / x.layout.voxel_mm[axis];
      ++steps;
    }
    q.profiles.push_back(std::move(p));
  }
  if (steps) {
    q.profile_gradient_per_mm2 = gradient / static_cast<double>(steps);
    q.truth_profile_gradient_per_mm2 = truth_gradient / static_cast<double>(steps);
  }
}

// x ~ sum_m a_m t_m by least squares over the region (normal equations: a handful of materials),
// then the RMSE of what is left.
void add_level_matched(const Volume& x, const SampleRegion& region, const std::vector<MaterialVolume>& materials,
                       TrajectoryQuality& q) {
  const auto m_count = static_cast<Eigen::Index>(materials.size());
  for (const MaterialVolume& m : materials)
    if (!(m.volume.layout == x.layout))
      throw std::invalid_argument("trajectory_quality: the material '" + m.material + "' must have the reconstruction's layout");
  std::vector<std::size_t> inside;
  const auto& n = x.layout.size;
  for (int k = 0; k < n[2]; ++k)
    for (int j = 0; j < n[1]; ++j)
      for (int i = 0; i < n[0]; ++i)
        if (region.contains(x.layout.centre_of(i, j, k))) inside.push_back(x.index(i, j, k));
  if (inside.empty()) return;
  Eigen::MatrixXd normal = Eigen::MatrixXd::Zero(m_count, m_count);
  Eigen::VectorXd right = Eigen::VectorXd::Zero(m_count);
  for (const std::size_t v : inside)
    for (Eigen::Index a = 0; a < m_count; ++a) {
      const double ta = materials[static_cast<std::size_t>(a)].volume.data[v];
      if (ta == 0) continue;
      right(a) += ta * x.data[v];
      for (Eigen::Index b = 0; b < m_count; ++b) normal(a, b) += ta * materials[static_cast<std::size_t>(b)].volume.data[v];
    }
  // A material absent from the region has a zero row: the pseudo-inverse leaves its level at 0.
  const Eigen::VectorXd level = normal.completeOrthogonalDecomposition().solve(right);
  double sum2 = 0;
  for (const std::size_t v : inside) {
    double fitted = 0;
    for (Eigen::Index a = 0; a < m_count; ++a) fitted += level(a) * materials[static_cast<std::size_t>(a)].volume.data[v];
    const double d = x.data[v] - fitted;
    sum2 += d * d;
  }
  q.rmse_level_matched_per_mm = std::sqrt(sum2 / static_cast<double>(inside.size()));
  for (Eigen::Index a = 0; a < m_count; ++a)
    if (normal(a, a) > 0) q.material_levels.push_back({materials[static_cast<std::size_t>(a)].material, level(a)});
}

}  // namespace

TrajectoryQuality trajectory_quality(const Volume& x, const Volume& truth, const SampleRegion& region,
                                     const std::array<int, 3>& through, float absorber_above_per_mm,
                                     const std::vector<MaterialVolume>& materials) {
  if (!(x.layout == truth.layout))
    throw std::invalid_argument("trajectory_quality: the truth must have the reconstruction's layout");
  TrajectoryQuality q;
  add_rmse(x, truth, region, absorber_above_per_mm, q);
  add_edge_gradients(x, truth, region, q);
  add_line_profiles(x, truth, region, through, q);
  if (!materials.empty()) add_level_matched(x, region, materials, q);
  return q;
}

}  // namespace ctk

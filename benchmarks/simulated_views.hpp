#pragma once
// The benchmarks' data: exact projections of an analytic phantom (2 x 2 rays per pixel) with
// Poisson noise for a given open-beam count, as line integrals and their weights (the detected
// share of the open beam's counts), and the phantom's voxelised truth.
#include <algorithm>
#include <cmath>
#include <iostream>
#include <random>
#include <string>
#include <vector>

#include "ctk/core/projection_stack.hpp"
#include "ctk/geom/projection_matrix.hpp"
#include "ctk/geom/trajectory.hpp"
#include "ctk/phantoms/builtin_phantoms.hpp"
#include "ctk/phantoms/detector_response.hpp"
#include "ctk/phantoms/render.hpp"
#include "ctk/proj/standard_problem.hpp"

namespace ctk::bench {

struct SimulatedViews {
  ProjectionStack b, w;
  ProjectionStack expected;  // the line integrals without photon noise
};

/// One view per direction (the beam along it in the phantom's frame), the source `sod_mm` from the
/// origin and `sdd_mm` from the detector, the detector centred on the beam.
inline std::vector<ProjectionMatrix> views_along(const std::vector<Eigen::Vector3d>& directions, const Detector& detector,
                                                 double sod_mm, double sdd_mm) {
  const Intrinsics K = Intrinsics::from_setup(sdd_mm, detector, detector.centre_px());
  std::vector<ProjectionMatrix> views;
  for (const auto& d : directions)
    views.push_back(ProjectionMatrix::compose(K, make_rigid(rotation_looking_along(d), Eigen::Vector3d(0, 0, sod_mm))));
  return views;
}

/// The phantom seen in `views`, noise seeded per view from `seed`.
inline SimulatedViews simulate_views(const Phantom& phantom, const std::vector<ProjectionMatrix>& views, const Detector& detector,
                                     double flat_counts, unsigned seed) {
  SimulatedViews s;
  const int n = static_cast<int>(views.size());
  s.b = ProjectionStack(n, detector.rows, detector.cols);
  s.w = ProjectionStack(n, detector.rows, detector.cols);
  s.expected = ProjectionStack(n, detector.rows, detector.cols);
  const CountsModel counts{flat_counts, 0};
#pragma omp parallel for schedule(dynamic)
  for (int v = 0; v < n; ++v) {
    const Image p = render_line_integrals(phantom, views[static_cast<std::size_t>(v)], detector, {2, std::nullopt, std::nullopt});
    std::copy(p.pixels.begin(), p.pixels.end(), s.expected.view(v));
    Image I = expected_counts(p, counts);
    std::mt19937_64 rng(seed + static_cast<unsigned>(v));
    draw_counts(I, counts, rng);
    for (std::size_t k = 0; k < I.pixels.size(); ++k) {
      const double detected = std::max(double(I.pixels[k]), 1.0) / flat_counts;
      s.b.view(v)[k] = static_cast<float>(-std::log(detected));
      s.w.view(v)[k] = static_cast<float>(detected);
    }
  }
  return s;
}

/// Root mean square of x - truth over every voxel.
inline double rmse(const Volume& x, const Volume& truth) {
  double sum = 0;
  const std::ptrdiff_t n = static_cast<std::ptrdiff_t>(x.data.size());
#pragma omp parallel for reduction(+ : sum)
  for (std::ptrdiff_t i = 0; i < n; ++i)
    sum += std::pow(double(x.data[static_cast<std::size_t>(i)]) - truth.data[static_cast<std::size_t>(i)], 2);
  return std::sqrt(sum / double(n));
}

/// The solver benchmarks' problem: the standard problem's geometry (`scale` divides its sizes),
/// its detector, a Shepp-Logan filling about 84 % of the volume (about 2 line-integral units
/// across) or a built-in sample by name, its views at `flat_counts`, and the truth sampled at the
/// voxel centres.
struct StandardProblemData {
  StandardProblem problem;
  Detector detector;
  Phantom phantom;
  SimulatedViews views;
  Volume truth;
};

inline StandardProblemData standard_problem_data(StandardTrajectory trajectory, int views, int scale, double flat_counts,
                                                 const std::string& phantom = "shepp-logan") {
  StandardProblemData d;
  d.problem = standard_problem(trajectory, views, scale);
  const StandardProblem& p = d.problem;
  d.detector = Detector{p.cols, p.rows, 1.6 * scale, 1.6 * scale};
  const double half_mm = 0.42 * p.layout.size[0] * p.layout.voxel_mm.x();
  d.phantom = phantom == "shepp-logan" ? shepp_logan_phantom(half_mm, 0.02 * 24.0 / half_mm) : builtin_phantom(phantom);
  std::cerr << "rendering " << p.views.size() << " views of " << p.cols << " x " << p.rows << " ...\n";
  d.views = simulate_views(d.phantom, p.views, d.detector, flat_counts, 1000);
  d.truth = Volume(p.layout);
  for (int k = 0; k < p.layout.size[2]; ++k)
    for (int j = 0; j < p.layout.size[1]; ++j)
      for (int i = 0; i < p.layout.size[0]; ++i)
        d.truth.at(i, j, k) = static_cast<float>(d.phantom.attenuation_at(p.layout.centre_of(i, j, k)));
  return d;
}

}  // namespace ctk::bench

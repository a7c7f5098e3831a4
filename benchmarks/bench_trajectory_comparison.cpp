// Circular against spherical, as the reference thesis compared them: a sample scanned along a
// circle about its axis and along the same number of directions spread over the sphere (HEALPix
// cell centres), each reconstructed by the same weighted least squares, scored against the
// voxelised truth by the RMSE and by the gradient magnitude across the truth's edges, on three
// line profiles through the sample's centre of mass (the thesis' figure) and on every
// axis-parallel line (the stable one; trajectory_quality.hpp). The circle misses data for planes
// off its mid-plane (Tuy's condition), so what the sphere gains grows with the cone angle: the
// comparison runs at several source distances (the detector at twice that, the magnification 2).
//   bench_trajectory_comparison [--phantom brick-and-plate] [--nside 5] [--size 112] [--voxel 0.45]
//                               [--sod 100,150,250,500] [--counts 10000] [--iterations 30] [--lambda 2]
//                               [--out F.json] [--pictures DIR]
#include <CLI/CLI.hpp>
#include <filesystem>
#include <iostream>
#include <string>

#include "ctk/core/atomic_write.hpp"
#include "ctk/core/machine.hpp"
#include "ctk/core/slice_preview.hpp"
#include "ctk/plan/plan_pictures.hpp"
#include "ctk/proj/joseph_operator.hpp"
#include "ctk/recon/wls_cg.hpp"
#include "phantom_truth.hpp"
#include "simulated_views.hpp"

namespace {

using namespace ctk;

nlohmann::json figures(const TrajectoryQuality& q) {
  return {{"rmse_per_mm", q.rmse_per_mm},
          {"edge_gradient_per_mm2", q.edge_gradient_per_mm2},
          {"edge_gradient_along_xyz_per_mm2", q.edge_gradient_along_per_mm2},
          {"profile_gradient_per_mm2", q.profile_gradient_per_mm2}};
}

}  // namespace

int main(int argc, char** argv) try {
  std::string phantom_name = "brick-and-plate", out, pictures;
  std::vector<double> sods{100, 150, 250, 500};
  int nside = 5, size = 112, iterations = 30;
  double voxel = 0.45, counts = 1e4, lambda = 2;
  CLI::App app{"Circular against spherical trajectories of the same number of views"};
  app.add_option("--phantom", phantom_name, "Built-in phantom")->capture_default_str();
  app.add_option("--nside", nside, "HEALPix resolution of the spherical views (12 nside^2 views, the circle as many)")
      ->capture_default_str();
  app.add_option("--size", size, "Voxels across")->capture_default_str();
  app.add_option("--voxel", voxel, "Voxel (mm)")->capture_default_str();
  app.add_option("--sod", sods, "Source distances (mm), comma separated; the detector at twice each")
      ->delimiter(',')
      ->capture_default_str();
  app.add_option("--counts", counts, "Open-beam counts")->capture_default_str();
  app.add_option("--iterations", iterations, "WLS-CG iterations")->capture_default_str();
  app.add_option("--lambda", lambda, "Gradient penalty")->capture_default_str();
  app.add_option("--out", out, "JSON to write");
  app.add_option("--pictures", pictures, "Folder for the pictures");
  CLI11_PARSE(app, argc, argv);
  const bench::PhantomTruth t = bench::phantom_truth(phantom_name, size, voxel);
  const Volume& truth = t.truth;

  const std::vector<Eigen::Vector3d> spherical = HealpixSphere(nside).directions();
  const int views = static_cast<int>(spherical.size());
  std::vector<Eigen::Vector3d> circular;  // the beam turning in the sample's mid-plane, about its axis +z
  for (const auto& R : circular_rotations(Eigen::Vector3d::UnitZ(), views, 0.0, 2 * M_PI))
    circular.push_back(R * Eigen::Vector3d::UnitX());

  const Detector detector = bench::detector_at_magnification_2(t);
  const int pixels = detector.cols;
  nlohmann::json result = {{"cpu", cpu_identity()},
                           {"problem",
                            {{"phantom", phantom_name},
                             {"views", views},
                             {"spherical", "HEALPix cell centres, nside " + std::to_string(nside)},
                             {"volume", {size, size, size}},
                             {"voxel_mm", voxel},
                             {"detector", {pixels, pixels}},
                             {"pixel_mm", 2 * voxel},
                             {"flat_counts", counts},
                             {"solver", "weighted least squares, gradient penalty lambda " + std::to_string(lambda) + ", " +
                                            std::to_string(iterations) + " CG iterations"},
                             {"profile_through_voxel", t.through}}}};
  std::cout << phantom_name << ", " << views << " views each, " << size << "^3 at " << voxel << " mm:\n"
            << "  SOD (mm)  cone half-angle  RMSE circular  spherical   edge gradient circular  spherical  gain   along z "
               "circular  spherical  gain   profile gradient circular  spherical  gain\n";
  for (const double sod : sods) {
    const double sdd = 2 * sod;
    const double cone_deg = std::atan(0.5 * pixels * detector.pitch_v_mm / sdd) * 180 / M_PI;
    nlohmann::json row = {{"sod_mm", sod}, {"sdd_mm", sdd}, {"cone_half_angle_deg", cone_deg}};
    std::vector<Volume> volumes;
    std::vector<TrajectoryQuality> quality;
    for (const auto* directions : std::initializer_list<const std::vector<Eigen::Vector3d>*>{&circular, &spherical}) {
      const std::vector<ProjectionMatrix> P = bench::views_along(*directions, detector, sod, sdd);
      const bench::SimulatedViews data = bench::simulate_views(t.phantom, P, detector, counts, 17);
      Volume x(t.layout);
      WlsOptions o;
      o.iterations = iterations;
      o.lambda = lambda;
      o.regulariser = Regulariser::gradient;
      solve_wls_cg(JosephOperator(P, t.layout, detector.rows, detector.cols), data.b, &data.w, x, o);
      quality.push_back(trajectory_quality(x, truth, t.region, t.through, bench::kNoAbsorbers));
      volumes.push_back(std::move(x));
    }
    const auto gain = [](double circle, double sphere) { return 100 * (sphere / circle - 1); };
    row["circular"] = figures(quality[0]);
    row["spherical"] = figures(quality[1]);
    row["edge_gradient_gain_percent"] = gain(quality[0].edge_gradient_per_mm2, quality[1].edge_gradient_per_mm2);
    row["profile_gradient_gain_percent"] = gain(quality[0].profile_gradient_per_mm2, quality[1].profile_gradient_per_mm2);
    row["edge_gradient_along_z_gain_percent"] =
        gain(quality[0].edge_gradient_along_per_mm2[2], quality[1].edge_gradient_along_per_mm2[2]);
    row["truth_edge_gradient_per_mm2"] = quality[0].truth_edge_gradient_per_mm2;
    row["truth_profile_gradient_per_mm2"] = quality[0].truth_profile_gradient_per_mm2;
    result["comparisons"].push_back(row);
    std::printf("  %8.0f  %15.1f  %13.5f  %9.5f   %22.5f  %9.5f  %+5.0f%%  %16.5f  %9.5f  %+5.0f%%  %25.5f  %9.5f  %+5.0f%%\n",
                sod, cone_deg, quality[0].rmse_per_mm, quality[1].rmse_per_mm, quality[0].edge_gradient_per_mm2,
                quality[1].edge_gradient_per_mm2, row["edge_gradient_gain_percent"].get<double>(),
                quality[0].edge_gradient_along_per_mm2[2], quality[1].edge_gradient_along_per_mm2[2],
                row["edge_gradient_along_z_gain_percent"].get<double>(), quality[0].profile_gradient_per_mm2,
                quality[1].profile_gradient_per_mm2, row["profile_gradient_gain_percent"].get<double>());
    if (!pictures.empty()) {
      // The comparison the planner draws (slices across z, x profiles), and a slice along the
      // axis through the centre of mass, where the circle's missing data show.
      const std::filesystem::path dir = pictures;
      std::filesystem::create_directories(dir);
      const std::string stem = phantom_name + "-sod" + std::to_string(static_cast<int>(sod));
      write_trajectory_comparison_png({{"circular", &volumes[0], quality[0]}, {"spherical", &volumes[1], quality[1]}}, truth,
                                      dir / (stem + "-comparison.png"));
      const float high = t.peak;
      const char* names[] = {"circular", "spherical"};
      for (std::size_t k = 0; k < 2; ++k)
        write_slice_preview(volumes[k], 1, t.through[1], 0.0f, 1.2f * high, "1/mm", dir / (stem + "-" + names[k] + "-xz.png"));
      write_slice_preview(truth, 1, t.through[1], 0.0f, 1.2f * high, "1/mm", dir / (stem + "-truth-xz.png"));
    }
  }
  if (!out.empty()) write_text_atomically(out, result.dump(1) + "\n");
  return 0;
} catch (const std::exception& e) {  // a file that cannot be written, a phantom that is not there
  std::cerr << e.what() << "\n";
  return 1;
}

// Few views: the edge-preserving Huber penalty against the best quadratic one. A phantom seen
// from 30 to 60 directions on a circle, with Poisson noise, is reconstructed by OS-SQS (the same
// solver for both penalties, so only the penalty differs) with the gradient penalty and with the
// Huber penalty of neighbour differences, each at a range of weights four times apart; for each
// penalty the weight with the least RMSE against the voxelised truth is kept and its edge
// gradient (the mean |d mu / ds| across the truth's edges on every axis-parallel line,
// trajectory_quality.hpp) compared. The Huber delta follows a rule: a quarter of the phantom's
// smallest contrast (the least |attenuation| of its primitives), so noise below it is smoothed
// quadratically and the phantom's edges, above it, are penalised linearly.
// The least-RMSE weights differ in noise as well as in edges, so the two penalties are also set
// side by side at equal noise: a weight's noise is the spread, over the scored region, of what the
// photon noise alone changes (the reconstruction from the noisy views less the one from the
// noise-free line integrals, same weights and solver); each quadratic weight's edge gradient is
// set against the Huber penalty's at that noise, read off the line through the two Huber weights
// whose noise brackets it.
//   bench_edge_preserving [--phantom shepp-logan|sample-2|...] [--size 96] [--voxel 0.6] [--views 30,40,60]
//                         [--counts 2000] [--epochs 20] [--out F.json] [--pictures DIR]
#include <CLI/CLI.hpp>
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <iostream>
#include <optional>
#include <string>

#include "ctk/core/atomic_write.hpp"
#include "ctk/core/machine.hpp"
#include "ctk/core/slice_preview.hpp"
#include "ctk/plan/plan_pictures.hpp"
#include "ctk/proj/joseph_operator.hpp"
#include "ctk/recon/ordered_subsets.hpp"
#include "ctk/recon/os_sqs.hpp"
#include "phantom_truth.hpp"
#include "simulated_views.hpp"

namespace {

using namespace ctk;

double smallest_contrast(const Phantom& phantom) {
  double least = 1e30;
  for (const Primitive& p : phantom.primitives)
    if (p.attenuation_per_mm != 0) least = std::min(least, std::abs(p.attenuation_per_mm));
  return least;
}

struct Tried {
  double lambda = 0, rmse = 0, noise = 0, edge = 0;
};

struct Best {
  double lambda = 0;
  TrajectoryQuality quality;
  Volume x;
  std::vector<Tried> tried;
};

// The standard deviation of x - clean over the region's voxels.
double noise_in_region(const Volume& x, const Volume& clean, const SampleRegion& region) {
  double sum = 0, sum2 = 0, n = 0;
  const auto& s = x.layout.size;
  for (int k = 0; k < s[2]; ++k)
    for (int j = 0; j < s[1]; ++j)
      for (int i = 0; i < s[0]; ++i)
        if (region.contains(x.layout.centre_of(i, j, k))) {
          const double d = x.at(i, j, k) - clean.at(i, j, k);
          sum += d;
          sum2 += d * d;
          n += 1;
        }
  return n > 0 ? std::sqrt(std::max(sum2 / n - (sum / n) * (sum / n), 0.0)) : 0.0;
}

// The Huber penalty's edge gradient at `noise`, linear between the two weights whose noise
// brackets it (noise falls as the weight grows); none outside their range.
std::optional<double> edge_at_noise(std::vector<Tried> huber, double noise) {
  std::sort(huber.begin(), huber.end(), [](const Tried& a, const Tried& b) { return a.noise < b.noise; });
  for (std::size_t i = 1; i < huber.size(); ++i) {
    const Tried &lo = huber[i - 1], &hi = huber[i];
    if (noise < lo.noise || noise > hi.noise) continue;
    const double f = hi.noise > lo.noise ? (noise - lo.noise) / (hi.noise - lo.noise) : 0.0;
    return lo.edge + f * (hi.edge - lo.edge);
  }
  return std::nullopt;
}

}  // namespace

int main(int argc, char** argv) try {
  std::string phantom_name = "shepp-logan", out, pictures;
  std::vector<int> view_counts{30, 40, 60};
  int size = 96, epochs = 20;
  double voxel = 0.6, counts = 2000;
  CLI::App app{"Few views: the Huber penalty against the best quadratic one"};
  app.add_option("--phantom", phantom_name, "Built-in phantom")->capture_default_str();
  app.add_option("--size", size, "Voxels across")->capture_default_str();
  app.add_option("--voxel", voxel, "Voxel (mm)")->capture_default_str();
  app.add_option("--views", view_counts, "View counts on the circle, comma separated")->delimiter(',')->capture_default_str();
  app.add_option("--counts", counts, "Open-beam counts")->capture_default_str();
  app.add_option("--epochs", epochs, "OS-SQS epochs")->capture_default_str();
  app.add_option("--out", out, "JSON to write");
  app.add_option("--pictures", pictures, "Folder for the pictures");
  CLI11_PARSE(app, argc, argv);
  const bench::PhantomTruth t = bench::phantom_truth(phantom_name, size, voxel);
  const Volume& truth = t.truth;
  const double delta = 0.25 * smallest_contrast(t.phantom);
  const double sod = 250, sdd = 500;  // magnification 2
  const Detector detector = bench::detector_at_magnification_2(t);
  const int pixels = detector.cols;
  const std::vector<double> weights = {0.5, 2, 8, 32, 128, 512, 2048};

  nlohmann::json result = {{"cpu", cpu_identity()},
                           {"problem",
                            {{"phantom", phantom_name},
                             {"volume", {size, size, size}},
                             {"voxel_mm", voxel},
                             {"detector", {pixels, pixels}},
                             {"sod_mm", sod},
                             {"sdd_mm", sdd},
                             {"flat_counts", counts},
                             {"solver", "OS-SQS, " + std::to_string(epochs) + " epochs, about 8 views per subset, non-negative"},
                             {"huber_delta_per_mm", delta},
                             {"weights_tried", weights}}}};
  std::cout << phantom_name << " (" << size << "^3 at " << voxel << " mm, " << counts << " counts, Huber delta " << delta
            << " /mm):\n  views  penalty    best lambda  RMSE (1/mm)  edge gradient (1/mm^2, truth's "
            << trajectory_quality(truth, truth, t.region, t.through, bench::kNoAbsorbers).truth_edge_gradient_per_mm2 << ")\n";
  for (const int views : view_counts) {
    std::vector<Eigen::Vector3d> directions;
    for (const auto& R : circular_rotations(Eigen::Vector3d::UnitZ(), views, 0.0, 2 * M_PI))
      directions.push_back(R * Eigen::Vector3d::UnitX());
    const std::vector<ProjectionMatrix> P = bench::views_along(directions, detector, sod, sdd);
    const bench::SimulatedViews data = bench::simulate_views(t.phantom, P, detector, counts, 29);
    const JosephOperator A(P, t.layout, detector.rows, detector.cols);
    const auto subsets = ordered_subsets(P, std::max(1, views / 8));
    const auto best_of = [&](double huber_delta) {
      Best best;
      for (const double lambda : weights) {
        OsSqsOptions o;
        o.epochs = epochs;
        o.lambda = lambda;
        o.regulariser = Regulariser::gradient;
        o.huber_delta = huber_delta;
        Volume x(t.layout), clean(t.layout);
        solve_os_sqs(A, data.b, &data.w, x, subsets, o);
        solve_os_sqs(A, data.expected, &data.w, clean, subsets, o);
        const TrajectoryQuality q = trajectory_quality(x, truth, t.region, t.through, bench::kNoAbsorbers);
        best.tried.push_back({lambda, q.rmse_per_mm, noise_in_region(x, clean, t.region), q.edge_gradient_per_mm2});
        if (best.x.data.empty() || q.rmse_per_mm < best.quality.rmse_per_mm) {
          best.lambda = lambda;
          best.quality = q;
          best.x = std::move(x);
        }
      }
      return best;
    };
    const Best quadratic = best_of(0), huber = best_of(delta);
    nlohmann::json row = {{"views", views}};
    for (const auto& [name, b] : {std::pair<const char*, const Best*>{"quadratic", &quadratic}, {"huber", &huber}}) {
      nlohmann::json tried = nlohmann::json::array();
      for (const Tried& w : b->tried)
        tried.push_back(
            {{"lambda", w.lambda}, {"rmse_per_mm", w.rmse}, {"noise_per_mm", w.noise}, {"edge_gradient_per_mm2", w.edge}});
      row[name] = {{"lambda", b->lambda},
                   {"rmse_per_mm", b->quality.rmse_per_mm},
                   {"edge_gradient_per_mm2", b->quality.edge_gradient_per_mm2},
                   {"tried", tried}};
      std::printf("  %5d  %-9s  %11.0f  %11.6f  %13.6f\n", views, name, b->lambda, b->quality.rmse_per_mm,
                  b->quality.edge_gradient_per_mm2);
    }
    row["rmse_ratio"] = huber.quality.rmse_per_mm / quadratic.quality.rmse_per_mm;
    row["edge_gradient_ratio"] = huber.quality.edge_gradient_per_mm2 / quadratic.quality.edge_gradient_per_mm2;
    nlohmann::json equal_noise = nlohmann::json::array();
    for (const Tried& q : quadratic.tried) {
      const std::optional<double> h = edge_at_noise(huber.tried, q.noise);
      if (!h) continue;
      equal_noise.push_back({{"quadratic_lambda", q.lambda},
                             {"noise_per_mm", q.noise},
                             {"quadratic_edge_gradient_per_mm2", q.edge},
                             {"huber_edge_gradient_per_mm2", *h},
                             {"ratio", *h / q.edge}});
      std::printf("  %5d  at noise %.6f /mm (quadratic lambda %g): edge gradient %.6f quadratic, %.6f Huber, %.2f x\n", views,
                  q.noise, q.lambda, q.edge, *h, *h / q.edge);
    }
    row["equal_noise"] = equal_noise;
    result["comparisons"].push_back(row);
    if (!pictures.empty()) {
      const std::filesystem::path dir = pictures;
      std::filesystem::create_directories(dir);
      const std::string stem = phantom_name + "-" + std::to_string(views) + "-views";
      write_trajectory_comparison_png({{"quadratic", &quadratic.x, quadratic.quality}, {"huber", &huber.x, huber.quality}}, truth,
                                      dir / (stem + "-penalties.png"));
      const float high = t.peak;
      // Shepp-Logan's inner contrasts are a few percent of its skull: a window on them.
      const float top = phantom_name == "shepp-logan" ? 0.4f * high : 1.1f * high;
      write_slice_preview(quadratic.x, 2, t.through[2], 0.0f, top, "1/mm", dir / (stem + "-quadratic.png"));
      write_slice_preview(huber.x, 2, t.through[2], 0.0f, top, "1/mm", dir / (stem + "-huber.png"));
      write_slice_preview(truth, 2, t.through[2], 0.0f, top, "1/mm", dir / (stem + "-truth.png"));
    }
  }
  if (!out.empty()) write_text_atomically(out, result.dump(1) + "\n");
  return 0;
} catch (const std::exception& e) {  // a file that cannot be written, a phantom that is not there
  std::cerr << e.what() << "\n";
  return 1;
}

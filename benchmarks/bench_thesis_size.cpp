// The thesis' size (a 720^3 volume from 900 views of 720^2) planned and measured on a sample of
// its views, then extrapolated to the whole scan: how long OS-SQS and WLS-CG take to the quality
// of 30 WLS-CG iterations, and whether they fit in memory.
//
// What is measured, on the full 720^3 volume: a forward and a back projection of `--sample` of the
// 900 views (evenly spread over the scan), and each solver's own run on those views (OS-SQS: its
// 24 subset updates per epoch; WLS-CG: its vector updates per iteration). The projections scale
// with the views exactly (the projector's work per view does not depend on the others), the
// solvers' volume updates do not scale at all, so one epoch of the whole scan is
//   projection seconds x 900 / sample + (epoch seconds - projection seconds) on the sample.
// How many epochs OS-SQS needs to reach the RMSE of 30 WLS-CG iterations is read from a
// time-to-quality result of the standard problem (bench_time_to_quality, `--quality`); the
// assumption is that the count of epochs to a quality depends on the subsets, not on the size.
//   bench_thesis_size [--trajectory circular|spherical] [--size 720] [--views 900] [--sample 36]
//                     [--quality time_to_quality.json] [--out F.json]
#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <iostream>
#include <string>

#include "ctk/core/atomic_write.hpp"
#include "ctk/core/json_access.hpp"
#include "ctk/core/machine.hpp"
#include "ctk/geom/trajectory.hpp"
#include "ctk/proj/joseph_operator.hpp"
#include "ctk/recon/memory_plan.hpp"
#include "ctk/recon/ordered_subsets.hpp"
#include "ctk/recon/os_sqs.hpp"
#include "ctk/recon/reconstruction_run.hpp"
#include "ctk/recon/wls_cg.hpp"

namespace {

using namespace ctk;

double seconds_since(std::chrono::steady_clock::time_point t) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
}

// The standard problem's cone (source 1000 mm from the isocentre, 1500 mm from the detector, the
// volume filling the detector) sampled at `n` voxels and pixels across.
std::vector<ProjectionMatrix> thesis_views(const std::string& trajectory, int n, int views) {
  const Detector detector{n, n, 1.6 * 256 / n, 1.6 * 256 / n};
  const Intrinsics K = Intrinsics::from_setup(1500.0, detector, detector.centre_px());
  std::vector<Eigen::Vector3d> directions;
  if (trajectory == "circular")
    for (const auto& R : circular_rotations(Eigen::Vector3d::UnitZ(), views, 0.0, 2 * M_PI))
      directions.push_back(R * Eigen::Vector3d::UnitX());
  else
    directions = random_directions(views, 2026);
  std::vector<ProjectionMatrix> out;
  out.reserve(directions.size());
  for (const auto& d : directions)
    out.push_back(ProjectionMatrix::compose(K, make_rigid(rotation_looking_along(d), Eigen::Vector3d(0, 0, 1000.0))));
  return out;
}

// The epochs OS-SQS (at `subsets`, non-negative) needed to reach the target RMSE in a
// bench_time_to_quality result, linear between epochs; the CG iterations that defined it.
struct Quality {
  double os_epochs = 0;
  int cg_iterations = 0;
  double cg_seconds = 0, os_seconds = 0;  // in that run
};

Quality epochs_to_quality(const nlohmann::json& r, int subsets) {
  Quality q;
  const double target = r.at("target_rmse").get<double>();
  for (const auto& m : r.at("methods")) {
    const std::string method = m.at("method").get<std::string>();
    const auto rmse = m.at("rmse").get<std::vector<double>>();
    if (method == "wls-cg") {
      q.cg_iterations = static_cast<int>(rmse.size()) - 1;
      q.cg_seconds = m.at("seconds").get<std::vector<double>>().back();
    }
    if (method != "os-sqs" || m.at("subsets").get<int>() != subsets) continue;
    for (std::size_t k = 1; k < rmse.size(); ++k)
      if (rmse[k] <= target) {
        q.os_epochs = double(k - 1) + (rmse[k - 1] - target) / (rmse[k - 1] - rmse[k]);
        break;
      }
    q.os_seconds = m.at("seconds_to_target").get<double>();
  }
  if (q.os_epochs <= 0 || q.cg_iterations <= 0)
    throw std::runtime_error("the time-to-quality result has no wls-cg curve or no os-sqs curve at " + std::to_string(subsets) +
                             " subsets reaching its target");
  return q;
}

}  // namespace

int main(int argc, char** argv) try {
  std::string trajectory = "circular", quality_file, out;
  int n = 720, views = 900, sample = 36;
  CLI::App app{"The thesis' size planned and measured on a sample of its views"};
  app.add_option("--trajectory", trajectory, "circular or spherical")
      ->check(CLI::IsMember({"circular", "spherical"}))
      ->capture_default_str();
  app.add_option("--size", n, "Voxels across the volume, pixels across the detector")->capture_default_str();
  app.add_option("--views", views, "Views of the whole scan")->capture_default_str();
  app.add_option("--sample", sample, "Views measured")->capture_default_str();
  app.add_option("--quality", quality_file, "A bench_time_to_quality result of this machine: the epochs to quality");
  app.add_option("--out", out, "JSON to write");
  CLI11_PARSE(app, argc, argv);
  const int subsets = default_subset_count(views);
  const VolumeLayout layout = VolumeLayout::centred({n, n, n}, Eigen::Vector3d::Constant(256.0 / n));
  const std::vector<ProjectionMatrix> all = thesis_views(trajectory, n, views);
  std::vector<ProjectionMatrix> sampled;
  sampled.reserve(static_cast<std::size_t>(sample));
  for (int k = 0; k < sample; ++k) sampled.push_back(all[static_cast<std::size_t>(k * views / sample)]);

  // The plans for the whole scan, weighted as counts are.
  SolverShape cg, os;
  cg.weighted = os.weighted = true;
  os.method = ReconstructionMethod::os_sqs;
  const MemoryPlan cg_plan = plan_memory(cg, layout, views, n, n), os_plan = plan_memory(os, layout, views, n, n);
  std::cerr << "memory, WLS-CG: " << cg_plan.describe() << "\nmemory, OS-SQS: " << os_plan.describe() << "\n";

  // The sample's projections of a non-zero volume (the projector skips no voxel by value).
  const JosephOperator A(sampled, layout, n, n);
  Volume x(layout);
  std::fill(x.data.begin(), x.data.end(), 0.01f);
  ProjectionStack y(sample, n, n);
  double forward = 1e30, back = 1e30;
  for (int repeat = 0; repeat < 2; ++repeat) {
    auto t = std::chrono::steady_clock::now();
    A.apply(x, y);
    forward = std::min(forward, seconds_since(t));
    t = std::chrono::steady_clock::now();
    A.apply_adjoint(y, x);
    back = std::min(back, seconds_since(t));
  }
  const double pair = forward + back;
  std::cerr << sample << " views: forward " << forward << " s, back " << back << " s\n";

  // The solvers on the sample: what they spend beyond the projections.
  ProjectionStack w = y;
  std::fill(w.data.begin(), w.data.end(), 1.0f);
  double os_epoch = 0, cg_iteration = 0;
  {
    Volume v(layout);
    OsSqsOptions o;
    o.epochs = 2;
    o.lambda = 1;
    o.regulariser = Regulariser::gradient;
    std::vector<double> epoch_seconds;
    solve_os_sqs(A, y, &w, v, ordered_subsets(sampled, std::min(subsets, sample)), o,
                 [&](const IterationLog& log) { epoch_seconds.push_back(log.seconds); });
    os_epoch = epoch_seconds.back();  // the first entry includes the curvature's projection pair
  }
  {
    Volume v(layout);
    WlsOptions o;
    o.iterations = 2;
    o.lambda = 1;
    o.regulariser = Regulariser::gradient;
    std::vector<double> iteration_seconds;
    solve_wls_cg(A, y, &w, v, o, [&](const IterationLog& log) { iteration_seconds.push_back(log.seconds); });
    cg_iteration = iteration_seconds.back();
  }
  const double scale = double(views) / sample;
  const double os_overhead = std::max(0.0, os_epoch - pair), cg_overhead = std::max(0.0, cg_iteration - pair);
  const double thesis_pair = pair * scale;
  const double thesis_epoch = thesis_pair + os_overhead, thesis_cg_iteration = thesis_pair + cg_overhead;
  std::cerr << "on the sample: an OS-SQS epoch (" << std::min(subsets, sample) << " subsets) " << os_epoch
            << " s, a WLS-CG iteration " << cg_iteration << " s\n";

  nlohmann::json result = {
      {"cpu", cpu_identity()},
      {"problem",
       {{"trajectory", trajectory},
        {"volume", {n, n, n}},
        {"voxel_mm", 256.0 / n},
        {"views", views},
        {"detector", {n, n}},
        {"geometry", "source 1000 mm from the isocentre, 1500 mm from the detector (the standard problem's cone)"}}},
      {"memory_plan",
       {{"wls_cg", {{"bytes", cg_plan.total_bytes()}, {"plan", cg_plan.describe()}}},
        {"os_sqs", {{"bytes", os_plan.total_bytes()}, {"plan", os_plan.describe()}}},
        {"limit_bytes", 24'000'000'000ull}}},
      {"measured",
       {{"sample_views", sample},
        {"forward_seconds", forward},
        {"back_seconds", back},
        {"os_sqs_epoch_seconds", os_epoch},
        {"os_sqs_subsets", std::min(subsets, sample)},
        {"wls_cg_iteration_seconds", cg_iteration},
        {"peak_resident_bytes", peak_resident_bytes()}}},
      {"extrapolated",
       {{"projection_pair_seconds", thesis_pair},
        {"os_sqs_epoch_seconds", thesis_epoch},
        {"os_sqs_subsets", subsets},
        {"wls_cg_iteration_seconds", thesis_cg_iteration},
        {"how",
         "projections x views / sample, plus the solver's updates measured on the sample (they do not grow with "
         "the views)"}}}};
  std::cout << trajectory << " " << n << "^3 from " << views << " views of " << n << "^2 on "
            << cpu_identity().value("model_name", "") << ":\n  memory: WLS-CG " << cg_plan.describe() << "; OS-SQS "
            << os_plan.describe() << "\n  extrapolated: a projection pair " << thesis_pair << " s, an OS-SQS epoch "
            << thesis_epoch << " s, a WLS-CG iteration " << thesis_cg_iteration << " s\n";
  if (!quality_file.empty()) {
    const Quality q = epochs_to_quality(read_json_file(quality_file), subsets);
    const double cg_total = q.cg_iterations * thesis_cg_iteration;
    // OS-SQS: its curvature (one projection pair), then the epochs to the quality.
    const double os_total = thesis_pair + q.os_epochs * thesis_epoch;
    result["to_quality"] = {{"from", quality_file},
                            {"wls_cg_iterations", q.cg_iterations},
                            {"os_sqs_epochs", q.os_epochs},
                            {"wls_cg_seconds", cg_total},
                            {"os_sqs_seconds", os_total},
                            {"fraction_of_wls_cg_time", os_total / cg_total},
                            {"standard_problem_fraction", q.os_seconds / q.cg_seconds}};
    std::cout << "  to the quality of " << q.cg_iterations << " WLS-CG iterations (" << quality_file << "): OS-SQS "
              << q.os_epochs << " epochs + its curvature, " << os_total / 60 << " min; WLS-CG " << cg_total / 60 << " min; "
              << os_total / cg_total << " of WLS-CG's time\n";
  }
  if (!out.empty()) write_text_atomically(out, result.dump(1) + "\n");
  return 0;
} catch (const std::exception& e) {  // a file that cannot be written, a phantom that is not there
  std::cerr << e.what() << "\n";
  return 1;
}

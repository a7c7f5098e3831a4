// When should an unregularised iterative reconstruction stop? On noisy data its RMSE against the
// truth falls, reaches a minimum and rises again as the solver starts fitting the noise. This
// measures, per epoch (OS-SQS) or iteration (WLS-CG), the RMSE against the truth, the weighted
// data fit of views the solver never saw (one in `--held-out-every`, chosen as `ctk reconstruct`
// chooses them) and the relative change of the image, so a stopping rule is judged on what it
// chose: the run on the other views ended by HeldOutFit's rule, against the best iterate of that
// run and of the same solver on every view, and against today's fixed counts (8 epochs, 30
// iterations) on every view. Prints one line per solver; the curves go to the JSON.
//   bench_stopping_rule [--trajectory circular|spherical] [--scale 2] [--views 360]
//                       [--phantom shepp-logan] [--counts 1e4] [--epochs 16] [--cg-iterations 40]
//                       [--held-out-every 32] [--lambda 0] [--methods os-sqs wls-cg] [--result product] [--out F.json]
#include <CLI/CLI.hpp>
#include <algorithm>
#include <cmath>
#include <iostream>
#include <string>

#include "ctk/core/atomic_write.hpp"
#include "ctk/core/machine.hpp"
#include "ctk/phantoms/builtin_phantoms.hpp"
#include "ctk/proj/joseph_operator.hpp"
#include "ctk/proj/standard_problem.hpp"
#include "ctk/recon/held_out_fit.hpp"
#include "ctk/recon/ordered_subsets.hpp"
#include "ctk/recon/os_sqs.hpp"
#include "ctk/recon/reconstruction_run.hpp"
#include "ctk/recon/wls_cg.hpp"
#include "simulated_views.hpp"

namespace {

using namespace ctk;

struct Curve {
  std::string method;
  bool held_out = false;  // trained without the held-out views
  std::vector<double> rmse, held_out_fit, relative_change, seconds;
  int rule_stops = -1, rule_result = -1;  // held out: where HeldOutFit's rule ends the run, and the iterate it returns
  double rule_result_rmse = -1;           // the volume the product returns there (HeldOutFit::restore_best)
  nlohmann::json to_json() const {
    return {{"method", method},
            {"held_out", held_out},
            {"rmse", rmse},
            {"held_out_fit", held_out_fit},
            {"rule_stops", rule_stops},
            {"rule_result", rule_result},
            {"rule_result_rmse", rule_result_rmse},
            {"relative_change", relative_change},
            {"seconds", seconds}};
  }
};

ProjectionStack views_of(const ProjectionStack& s, const std::vector<int>& views) {
  ProjectionStack out(static_cast<int>(views.size()), s.rows, s.cols);
  const std::size_t n = static_cast<std::size_t>(s.rows) * static_cast<std::size_t>(s.cols);
  for (std::size_t k = 0; k < views.size(); ++k) std::copy_n(s.view(views[k]), n, out.view(static_cast<int>(k)));
  return out;
}

double norm(const Volume& x) {
  double sum = 0;
  for (float v : x.data) sum += double(v) * v;
  return std::sqrt(sum);
}

double distance(const Volume& a, const Volume& b) {
  double sum = 0;
  for (std::size_t i = 0; i < a.data.size(); ++i) sum += std::pow(double(a.data[i]) - b.data[i], 2);
  return std::sqrt(sum);
}

// The held-out rule's result as `--result` names it; "product": as reconstruction_run asks.
HeldOutResult result_choice(const std::string& name, const std::string& method) {
  if (name == "last-improving") return HeldOutResult::last_improving;
  if (name == "mean-of-last-two") return HeldOutResult::mean_of_last_two;
  if (name == "one-before") return HeldOutResult::one_before;
  return held_out_result(reconstruction_method(method));
}

}  // namespace

int main(int argc, char** argv) try {
  std::string trajectory = "circular", phantom_name = "shepp-logan", out;
  int scale = 2, views = 360, epochs = 16, cg_iterations = 40, holdout_every = 32;
  double counts = 1e4, lambda = 0;
  std::vector<std::string> methods = {"os-sqs", "wls-cg"};
  CLI::App app{"Stopping rules for unregularised iterative reconstruction, against the truth"};
  app.add_option("--trajectory", trajectory, "circular or spherical")
      ->check(CLI::IsMember({"circular", "spherical"}))
      ->capture_default_str();
  app.add_option("--scale", scale, "Divides every size of the standard problem")->capture_default_str();
  app.add_option("--views", views, "Views")->capture_default_str();
  app.add_option("--phantom", phantom_name, "shepp-logan (filling the volume) or a built-in sample")->capture_default_str();
  app.add_option("--counts", counts, "Open-beam counts per pixel (Poisson; 16-bit, so at most 60000)")
      ->check(CLI::Range(10.0, 60000.0))
      ->capture_default_str();
  app.add_option("--epochs", epochs, "OS-SQS epochs")->capture_default_str();
  app.add_option("--cg-iterations", cg_iterations, "WLS-CG iterations")->capture_default_str();
  app.add_option("--held-out-every", holdout_every, "Hold out one view in n (ReconstructionOptions::held_out_every)")
      ->capture_default_str();
  app.add_option("--lambda", lambda, "Identity penalty")->capture_default_str();
  app.add_option("--methods", methods, "Solvers to follow")->check(CLI::IsMember({"os-sqs", "wls-cg"}))->capture_default_str();
  std::string result_name = "product";
  app.add_option("--result", result_name, "The stopped run's result: as the product returns it, or another choice")
      ->check(CLI::IsMember({"product", "last-improving", "one-before", "mean-of-last-two"}))
      ->capture_default_str();
  app.add_option("--out", out, "JSON to write");
  CLI11_PARSE(app, argc, argv);

  const bench::StandardProblemData problem =
      bench::standard_problem_data(trajectory == "spherical" ? StandardTrajectory::spherical : StandardTrajectory::circular,
                                   views, scale, counts, phantom_name);
  const StandardProblem& p = problem.problem;
  const bench::SimulatedViews& data = problem.views;
  const Volume& truth = problem.truth;

  // The product's choice of views to hold out (ReconstructionOptions::held_out_every).
  const std::vector<int> held = held_out_positions(p.views, holdout_every);
  std::vector<int> all, trained;
  for (int v = 0; v < static_cast<int>(p.views.size()); ++v) {
    all.push_back(v);
    if (!std::binary_search(held.begin(), held.end(), v)) trained.push_back(v);
  }
  std::vector<ProjectionMatrix> held_views;
  held_views.reserve(held.size());
  for (int v : held) held_views.push_back(p.views[static_cast<std::size_t>(v)]);
  const auto A_held = std::make_shared<JosephOperator>(held_views, p.layout, p.rows, p.cols);

  std::vector<Curve> curves;
  for (const bool hold : {true, false}) {
    const std::vector<int>& used = hold ? trained : all;
    std::vector<ProjectionMatrix> used_views;
    used_views.reserve(used.size());
    for (int v : used) used_views.push_back(p.views[static_cast<std::size_t>(v)]);
    const JosephOperator A(used_views, p.layout, p.rows, p.cols);
    const ProjectionStack b = views_of(data.b, used), w = views_of(data.w, used);
    for (const std::string& method : methods) {
      Curve c{method, hold, {}, {}, {}, {}, -1, -1};
      Volume x(p.layout), previous(p.layout);
      HeldOutFit judge(A_held, views_of(data.b, held), views_of(data.w, held));
      judge.return_result(result_choice(result_name, method));
      const StoppingRule rule = judge.rule();
      // The volume the product would return where the rule ends the run (or at the limit).
      const auto score_result = [&] {
        Volume result = x;
        judge.restore_best(result);
        c.rule_result_rmse = bench::rmse(result, truth);
      };
      double clock = 0;
      const IterationCallback follow = [&](const IterationLog& log) {
        clock += log.seconds;
        c.seconds.push_back(clock);
        c.rmse.push_back(bench::rmse(x, truth));
        judge.observe(log.iteration, x);
        c.held_out_fit.push_back(judge.report()["fit"].back());
        if (hold && c.rule_stops < 0 && rule()) {  // the run would end here with the best iterate
          c.rule_stops = log.iteration;
          c.rule_result = judge.report()["best_iteration"];
          score_result();
        }
        c.relative_change.push_back(log.iteration == 0 ? 1.0 : distance(x, previous) / std::max(norm(x), 1e-30));
        previous = x;
        std::cerr << "  " << method << (hold ? " (held out)" : "") << " " << log.iteration << ": RMSE " << c.rmse.back()
                  << ", held-out fit " << c.held_out_fit.back() << ", change " << c.relative_change.back() << "\n";
      };
      if (method == "os-sqs") {
        OsSqsOptions o;
        o.epochs = epochs;
        o.lambda = lambda;
        solve_os_sqs(A, b, &w, x, ordered_subsets(used_views, default_subset_count(static_cast<int>(used.size()))), o, follow);
      } else {
        WlsOptions o;
        o.iterations = cg_iterations;
        o.lambda = lambda;
        o.tolerance = 0;
        o.gradient_after_last = false;
        solve_wls_cg(A, b, &w, x, o, follow);
      }
      if (hold && c.rule_stops < 0) score_result();
      curves.push_back(c);
    }
  }
  nlohmann::json result = {{"cpu", cpu_identity()},
                           {"problem",
                            {{"trajectory", trajectory},
                             {"scale", scale},
                             {"volume", p.layout.size},
                             {"views", p.views.size()},
                             {"held_out_views", held},
                             {"detector", {p.cols, p.rows}},
                             {"phantom", phantom_name},
                             {"counts", counts},
                             {"lambda", lambda},
                             {"result", result_name}}}};
  const auto best = [](const std::vector<double>& r) { return *std::min_element(r.begin(), r.end()); };
  for (const Curve& c : curves) {
    nlohmann::json j = c.to_json();
    if (c.held_out) {
      const Curve& every =
          *std::find_if(curves.begin(), curves.end(), [&](const Curve& o) { return !o.held_out && o.method == c.method; });
      const int fixed = std::min<int>(c.method == "os-sqs" ? 8 : 30, static_cast<int>(every.rmse.size()) - 1);
      const int result_at = c.rule_result >= 0 ? c.rule_result : static_cast<int>(c.rmse.size()) - 1;
      const double rule_rmse = c.rule_result_rmse;
      j["rule_iterate_rmse_over_own_best"] = c.rmse[static_cast<std::size_t>(result_at)] / best(c.rmse);
      j["rule_rmse_over_own_best"] = rule_rmse / best(c.rmse);
      j["rule_rmse_over_every_view_best"] = rule_rmse / best(every.rmse);
      j["fixed_count_rmse_over_every_view_best"] = every.rmse[static_cast<std::size_t>(fixed)] / best(every.rmse);
      j["rule_seconds_over_fixed_count"] = c.seconds[static_cast<std::size_t>(c.rule_stops >= 0 ? c.rule_stops : result_at)] /
                                           every.seconds[static_cast<std::size_t>(fixed)];
      std::cout << trajectory << " " << phantom_name << " " << counts << " counts, " << views << " views, " << c.method << ": "
                << (c.rule_stops >= 0 ? "stops after " + std::to_string(c.rule_stops) : std::string("runs to the limit"))
                << " with iterate " << result_at << ", RMSE " << rule_rmse << " = " << j["rule_rmse_over_own_best"].get<double>()
                << " x its own best (the iterate alone " << j["rule_iterate_rmse_over_own_best"].get<double>() << "), "
                << j["rule_rmse_over_every_view_best"].get<double>() << " x every view's best (fixed count " << fixed << ": "
                << j["fixed_count_rmse_over_every_view_best"].get<double>() << "), in "
                << j["rule_seconds_over_fixed_count"].get<double>() << " of the fixed count's time\n";
    }
    result["curves"].push_back(j);
  }
  if (!out.empty()) write_text_atomically(out, result.dump(1) + "\n");
  return 0;
} catch (const std::exception& e) {  // a file that cannot be written, a phantom that is not there
  std::cerr << e.what() << "\n";
  return 1;
}

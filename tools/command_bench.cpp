// ctk bench: throughput of the fast Joseph projector against the naive reference, measured in
// one run on the standard problem (libproj's projector_benchmark.hpp), as a table or JSON;
// --repeat gives medians of runs in which the two take turns; --simd runs the fast projector on
// a narrower SIMD target than the widest; --dump writes what the fast projector computed for
// benchmarks/yardstick.py.
#include <iostream>
#include <memory>

#include "commands.hpp"
#include "ctk/proj/joseph_projector.hpp"
#include "ctk/proj/projector_benchmark.hpp"

namespace ctk::tools {

namespace {

struct BenchCommandOptions {
  ProjectorBenchmarkOptions benchmark;
  bool json = false;
};

void run_bench(const BenchCommandOptions& o) {
  std::ostream& table = o.json ? std::cerr : std::cout;  // with --json, stdout holds the JSON alone
  const ProjectorBenchmark b = run_projector_benchmark(o.benchmark, [&](const std::string& line) { table << line << "\n"; });
  if (o.json) std::cout << b.report.dump(2) << "\n";
}

}  // namespace

void register_bench(CLI::App& app) {
  auto options = std::make_shared<BenchCommandOptions>();
  CLI::App* cmd = app.add_subcommand(
      "bench", "Projector throughput: fast (all threads) vs naive reference (1 thread) on the standard problem");
  cmd->add_option("--views", options->benchmark.views, "Views per trajectory")
      ->capture_default_str()
      ->check(CLI::Range(1, 100000));
  cmd->add_option("--reference-views", options->benchmark.reference_views,
                  "Views the reference is timed on (its time is scaled per view to --views)")
      ->capture_default_str()
      ->check(CLI::Range(1, 100000));
  cmd->add_option("--scale", options->benchmark.scale, "Divide volume and detector sizes by this (1 = the standard problem)")
      ->capture_default_str()
      ->check(CLI::Range(1, 64));
  cmd->add_option("--threads", options->benchmark.threads, "Threads for the fast projector (0 = all)")->capture_default_str();
  cmd->add_option("--repeat", options->benchmark.repeat,
                  "Time fast and reference this many times each, taking turns, and report the medians")
      ->capture_default_str()
      ->check(CLI::Range(1, 100));
  cmd->add_option("--simd", options->benchmark.simd,
                  "Run the fast projector on this SIMD target instead of the widest (to see what each gives)")
      ->check(CLI::IsMember(JosephProjector::simd_targets()));
  cmd->add_flag("--json", options->json, "Print the result as JSON on stdout (the table goes to stderr)");
  cmd->add_option("--dump", options->benchmark.dump,
                  "Write the fast projector's results on the reference's views, and on 16 neighbouring views, to this folder "
                  "(for benchmarks/yardstick.py)");
  cmd->callback([options] { run_bench(*options); });
}

}  // namespace ctk::tools

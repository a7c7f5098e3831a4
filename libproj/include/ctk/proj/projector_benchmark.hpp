#pragma once
// The projector benchmark (`ctk bench`, `ctk.bench`): the fast Joseph projector on all threads
// against the naive reference on one thread, in the same run, on the standard problem
// (standard_problem.hpp) circular and spherical, forward and back. The reference runs on a few
// views spread over the trajectory and its time is scaled per view to the whole set; the two agree
// to a stated relative difference on those views. With `repeat` the two take turns, a whole run
// each, and the medians count. `dump` writes what the fast projector computed on the reference's
// views and on neighbouring views, for benchmarks/yardstick.py to check with its own arithmetic.
#include <filesystem>
#include <functional>
#include <nlohmann/json.hpp>
#include <string>

namespace ctk {

struct ProjectorBenchmarkOptions {
  int views = 360;             // per trajectory
  int reference_views = 12;    // the reference is timed on these, spread evenly
  int scale = 1;               // volume and detector sizes divided by it (1: the standard problem)
  int threads = 0;             // the fast projector's (0: all)
  int repeat = 1;              // runs of each, taking turns; medians reported
  std::string simd;            // a narrower SIMD target than the widest (empty: the widest)
  std::filesystem::path dump;  // empty: no dump
  void validate() const;       // std::invalid_argument naming the field
};

struct ProjectorBenchmark {
  /// cpu, threads, simd, problem, forward and back (circular), spherical {forward, back}: each
  /// direction's fast and reference seconds (and every run's), speedup, voxel-views per second,
  /// the relative difference to the reference.
  nlohmann::json report;
  /// "circular forward 12.3x, back 10.1x; spherical forward 11.0x, back 9.8x (fast on N threads, TARGET)"
  std::string brief() const;
};

/// `log` receives the table line by line as each direction is measured.
ProjectorBenchmark run_projector_benchmark(const ProjectorBenchmarkOptions& options,
                                           const std::function<void(const std::string&)>& log = {});

}  // namespace ctk

#pragma once
// What an iterative solver reports after each iteration, and why it stopped.
#include <functional>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

namespace ctk {

struct IterationLog {
  int iteration = 0;             // 1-based; 0 is the starting point
  double cost = 0;               // the objective the solver minimises
  double data_term = 0;          // 1/2 ||W^(1/2) (A x - b)||^2 (SIRT: unweighted)
  double regulariser_term = 0;   // 1/2 lambda ||G x||^2
  double relative_gradient = 0;  // ||gradient|| / ||gradient at the start|| (CG)
  double seconds = 0;            // this iteration's wall time
};

struct SolverReport {
  std::vector<IterationLog> iterations;  // starting point first
  std::string stop_reason;
};

using IterationCallback = std::function<void(const IterationLog&)>;

/// Asked after every iteration, once the callback has seen it: a reason ends the run there as done
/// (the result stopped improving: held_out_fit.hpp). Unlike a stop on request, nothing is saved.
using StoppingRule = std::function<std::optional<std::string>()>;

nlohmann::json to_json(const SolverReport& report);

}  // namespace ctk

#include "ctk/recon/iteration_log.hpp"

namespace ctk {

nlohmann::json to_json(const SolverReport& report) {
  nlohmann::json iterations = nlohmann::json::array();
  for (const IterationLog& l : report.iterations)
    iterations.push_back({{"iteration", l.iteration},
                          {"cost", l.cost},
                          {"data_term", l.data_term},
                          {"regulariser_term", l.regulariser_term},
                          {"relative_gradient", l.relative_gradient},
                          {"seconds", l.seconds}});
  return {{"iterations", iterations}, {"stop_reason", report.stop_reason}};
}

}  // namespace ctk

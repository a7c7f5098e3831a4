#include "ctk/recon/memory_plan.hpp"

#include <unistd.h>

#include <cstdio>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include "ctk/recon/held_out_fit.hpp"

namespace ctk {

const char* to_string(ReconstructionMethod m) {
  switch (m) {
    case ReconstructionMethod::wls_cg:
      return "wls-cg";
    case ReconstructionMethod::os_sqs:
      return "os-sqs";
    case ReconstructionMethod::sirt:
      return "sirt";
    case ReconstructionMethod::fdk:
      return "fdk";
  }
  return "?";
}

ReconstructionMethod reconstruction_method(const std::string& name) {
  for (ReconstructionMethod m :
       {ReconstructionMethod::wls_cg, ReconstructionMethod::os_sqs, ReconstructionMethod::sirt, ReconstructionMethod::fdk})
    if (name == to_string(m)) return m;
  throw std::invalid_argument("method: expected wls-cg, os-sqs, sirt or fdk, got '" + name + "'");
}

std::size_t MemoryPlan::total_bytes() const {
  return static_cast<std::size_t>(volumes) * volume_bytes + static_cast<std::size_t>(stacks) * stack_bytes + other_bytes;
}

std::string MemoryPlan::describe() const {
  auto gb = [](std::size_t bytes) {
    char s[32];
    std::snprintf(s, sizeof s, "%.2f GB", static_cast<double>(bytes) / 1e9);
    return std::string(s);
  };
  std::ostringstream out;
  out << volumes << " volumes x " << gb(volume_bytes) << " + " << stacks << " stacks x " << gb(stack_bytes) << " + "
      << gb(other_bytes) << " = " << gb(total_bytes());
  return out.str();
}

MemoryPlan plan_memory(const SolverShape& solver, const VolumeLayout& layout, int views, int rows, int cols) {
  const bool weighted = solver.weighted;
  MemoryPlan plan;
  plan.volume_bytes = layout.voxel_count() * sizeof(float);
  plan.stack_bytes =
      static_cast<std::size_t>(views) * static_cast<std::size_t>(rows) * static_cast<std::size_t>(cols) * sizeof(float);
  switch (solver.method) {
    case ReconstructionMethod::wls_cg:
      plan.volumes = 4 + (solver.preconditioned ? 1 : 0);
      plan.stacks = 3 + (weighted ? 1 : 0);
      break;
    case ReconstructionMethod::os_sqs:
      plan.volumes = 5;  // and the Huber penalty's curvature
      plan.stacks = 2 + (weighted ? 1 : 0);
      break;
    case ReconstructionMethod::sirt:
      plan.volumes = 3;
      plan.stacks = 3;
      break;
    case ReconstructionMethod::fdk:
      plan.volumes = 1;
      plan.stacks = 1;
      break;
  }
  // Ray tables and images being read: small; keep 100 MB of margin for the process itself.
  plan.other_bytes = 100'000'000;
  if (solver.held_out_every > 0) {
    plan.volumes += held_out_volumes(held_out_result(solver.method));
    plan.other_bytes += 3 * (plan.stack_bytes / static_cast<std::size_t>(solver.held_out_every) +
                             static_cast<std::size_t>(rows) * static_cast<std::size_t>(cols) * sizeof(float));
  }
  return plan;
}

std::size_t available_memory_bytes() {
  std::ifstream meminfo("/proc/meminfo");
  std::string key;
  std::size_t kb = 0;
  std::string unit;
  while (meminfo >> key >> kb >> unit)
    if (key == "MemAvailable:") return kb * 1024;
  return static_cast<std::size_t>(sysconf(_SC_PHYS_PAGES)) * static_cast<std::size_t>(sysconf(_SC_PAGE_SIZE));
}

}  // namespace ctk

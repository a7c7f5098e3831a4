#pragma once
// How much memory a reconstruction needs before it starts, so a run that cannot fit is refused
// with the numbers instead of dying hours later.
#include <cstddef>
#include <string>

#include "ctk/core/volume.hpp"
#include "ctk/recon/regulariser.hpp"

namespace ctk {

enum class ReconstructionMethod { wls_cg, os_sqs, sirt, fdk };
const char* to_string(ReconstructionMethod m);
/// "wls-cg", "os-sqs", "sirt", "fdk"; std::invalid_argument naming the others.
ReconstructionMethod reconstruction_method(const std::string& name);

struct MemoryPlan {
  std::size_t volume_bytes = 0;  // one volume
  std::size_t stack_bytes = 0;   // one projection stack (the views used)
  int volumes = 0, stacks = 0;   // how many of each the method holds at once
  std::size_t other_bytes = 0;   // per-thread tables, one image per reader, margin

  std::size_t total_bytes() const;
  /// "4 volumes x 1.49 GB + 4 stacks x 1.87 GB + 0.10 GB = 13.53 GB"
  std::string describe() const;
};

/// What the plan needs of the solver: its method and penalty (slabs hold no neighbour planes, so
/// a penalty of neighbour differences cannot run on them), and OS-SQS's subsets.
struct SolverShape {
  ReconstructionMethod method = ReconstructionMethod::wls_cg;
  double lambda = 0;
  Regulariser regulariser = Regulariser::identity;
  double huber_delta = 0;
  bool weighted = false;
  bool preconditioned = false;  // WLS-CG's diagonal preconditioner: one more volume
  /// Stopped by one view in this many held out (held_out_fit.hpp; 0: not): the best iterate, one
  /// more volume, and the held-out views' data, weights and residual.
  int held_out_every = 0;
};

/// CG: x, gradient, direction, H direction (and the preconditioner); b, residual, scratch, and
/// weights when weighted.
/// OS-SQS: x, the extrapolated point, the curvature, the gradient, the Huber penalty's curvature; b,
/// weights when weighted, and
/// one subset's data, weights and residual (counted as a stack).
/// SIRT: x, column sums, update; b, row sums, residual. FDK: the volume and the filtered stack.
MemoryPlan plan_memory(const SolverShape& solver, const VolumeLayout& layout, int views, int rows, int cols);

/// Memory available to a new run (MemAvailable in /proc/meminfo; physical memory otherwise).
std::size_t available_memory_bytes();

}  // namespace ctk

#include "ctk/recon/distribution_plan.hpp"

#include <sstream>
#include <stdexcept>

namespace ctk {

const char* to_string(Decomposition d) {
  switch (d) {
    case Decomposition::automatic:
      return "auto";
    case Decomposition::views:
      return "views";
    case Decomposition::slabs:
      return "slabs";
  }
  return "?";
}

Decomposition decomposition_from_string(const std::string& name) {
  if (name == "auto") return Decomposition::automatic;
  if (name == "views") return Decomposition::views;
  if (name == "slabs") return Decomposition::slabs;
  throw std::invalid_argument("decomposition '" + name + "': expected auto, views or slabs");
}

namespace {

// The scalars a solver sums over the ranks per iteration (ProjectionOperator's sum_over_range and
// sum_over_domain; on views split the volume is every rank's, so sums over it are local).
std::size_t scalars_per_iteration(const SolverShape& s, bool slabs) {
  const bool penalty = s.lambda > 0;
  switch (s.method) {
    case ReconstructionMethod::wls_cg:  // the step's curvature and the data term; over slabs the gradient's norm (and
                                        // its preconditioned square), the penalties
      return 2 + (slabs ? 1 + (s.preconditioned ? 1 : 0) + (penalty ? 2 : 0) : 0);
    case ReconstructionMethod::sirt:  // the data term
      return 1;
    case ReconstructionMethod::os_sqs:  // the epoch's data term; its penalty over slabs
      return 1 + (slabs && penalty ? 1 : 0);
    case ReconstructionMethod::fdk:
      return 0;
  }
  return 0;
}

std::string refusal_for_slabs(const SolverShape& s) {
  if (s.method == ReconstructionMethod::fdk) return "fdk runs on one process";
  if (s.lambda > 0 && s.huber_delta > 0) return "the Huber penalty reads neighbouring voxels across the slabs";
  if (s.lambda > 0 && s.regulariser == Regulariser::gradient)
    return "the gradient penalty reads neighbouring voxels across the slabs";
  return {};
}

double gigabytes(std::size_t bytes) { return static_cast<double>(bytes) / 1e9; }

}  // namespace

std::string DistributionPlan::describe() const {
  std::ostringstream s;
  s << "views split: at most " << views_per_rank << " views and the whole volume on each of " << ranks << " ranks, "
    << views_memory.describe() << " per rank, " << gigabytes(views_bytes_per_iteration) * 1e3
    << " MB to the other ranks per iteration\n";
  if (slabs_refused.empty())
    s << "slabs: at most " << planes_per_rank << " planes and the rows they own on each rank, " << slabs_memory.describe()
      << " per rank, " << gigabytes(slabs_bytes_per_iteration) * 1e3 << " MB to the other ranks per iteration\n";
  else
    s << "slabs: not for this run (" << slabs_refused << ")\n";
  s << "picked: " << to_string(decomposition);
  return s.str();
}

DistributionPlan plan_distribution(const SolverShape& solver, const VolumeLayout& layout,
                                   const std::vector<ProjectionMatrix>& views, int rows, int cols, int subsets, int ranks,
                                   int rank, std::size_t available_bytes, Decomposition asked) {
  if (ranks < 1 || rank < 0 || rank >= ranks) throw std::invalid_argument("plan_distribution: rank outside 0 .. ranks - 1");
  DistributionPlan p;
  p.ranks = ranks;
  const int view_count = static_cast<int>(views.size());
  p.views_per_rank = (view_count + ranks - 1) / ranks;
  p.views_memory = plan_memory(solver, layout, p.views_per_rank, rows, cols);
  if (ranks == 1) return p;
  if (solver.method == ReconstructionMethod::fdk)
    throw std::invalid_argument("fdk runs on one process (it reads and filters each view once): start it without mpirun");

  const std::size_t volume_bytes = layout.voxel_count() * sizeof(float);
  const std::size_t volumes_summed = solver.method == ReconstructionMethod::os_sqs ? static_cast<std::size_t>(subsets) : 1;
  p.views_bytes_per_iteration = volumes_summed * volume_bytes + scalars_per_iteration(solver, false) * sizeof(double);

  p.slabs_refused = refusal_for_slabs(solver);
  if (p.slabs_refused.empty() && layout.size[2] < ranks)
    p.slabs_refused = std::to_string(ranks) + " ranks for " + std::to_string(layout.size[2]) + " planes";
  if (p.slabs_refused.empty()) {
    p.rows = std::make_shared<const SlabRows>(views, layout, rows, ranks);
    p.planes_per_rank = slab_planes(layout.size[2], 0, ranks).count;  // the first ranks hold the extra plane
    int owned = 1, reach = 1;
    for (int q = 0; q < ranks; ++q) {
      owned = std::max(owned, p.rows->owned_height(q));
      reach = std::max(reach, p.rows->footprint_height(q));
    }
    p.slabs_memory = plan_memory(solver, slab_layout(layout, 0, ranks), view_count, owned, cols);
    // The projection of the slab onto the rows it reaches, while a projection is exchanged.
    p.slabs_memory.other_bytes +=
        static_cast<std::size_t>(view_count) * static_cast<std::size_t>(reach) * static_cast<std::size_t>(cols) * sizeof(float);
    p.slabs_bytes_per_iteration = p.rows->exchanged_rows(rank) * static_cast<std::size_t>(cols) * sizeof(float) +
                                  scalars_per_iteration(solver, true) * sizeof(double);
  }

  const bool views_fit = p.views_memory.total_bytes() <= available_bytes;
  if (asked == Decomposition::views || (asked == Decomposition::automatic && (views_fit || !p.slabs_refused.empty()))) {
    p.decomposition = Decomposition::views;
  } else {
    if (!p.slabs_refused.empty()) throw std::invalid_argument("slabs cannot run here: " + p.slabs_refused);
    p.decomposition = Decomposition::slabs;
  }
  return p;
}

}  // namespace ctk

#pragma once
// What an iterative solver needs to continue exactly where it stopped: the iterate, the
// solver's own vectors (CG: residual, gradient, search direction) and scalars, and its log so far.
// A solver hands it over every few iterations and when asked to stop (Ctrl-C), and takes it
// back to continue; continued, it computes what the uninterrupted run would have.
#include <filesystem>
#include <functional>
#include <nlohmann/json.hpp>
#include <vector>

#include "ctk/core/float_buffer.hpp"
#include "ctk/core/volume.hpp"
#include "ctk/recon/iteration_log.hpp"

namespace ctk {

struct SolverState {
  std::string solver;                // "wls-cg", "sirt": a state is continued by the solver that made it
  int iteration = 0;                 // iterations done
  std::vector<IterationLog> log;     // starting point first
  Volume x;                          // the iterate
  std::vector<FloatBuffer> vectors;  // the solver's own
  std::vector<double> scalars;
};

/// The same, by reference to the solver's own vectors: saving copies nothing in memory.
struct SolverSnapshot {
  std::string solver;
  int iteration = 0;
  const std::vector<IterationLog>& log;
  const Volume& x;
  std::vector<const FloatBuffer*> vectors;
  std::vector<double> scalars;
};

struct Checkpointing {
  SolverState* resume = nullptr;  // continue from this state (its vectors are moved into the solver)
  int every = 0;                  // hand the state to `save` every `every` iterations (0: only when stopped)
  std::function<void(const SolverSnapshot&)> save;
  std::function<bool()> stop_requested;  // asked after every iteration: true saves the state and stops
};

/// The stop reason of a solver that saved its state and stopped on request.
inline constexpr const char* kStoppedOnRequest = "stopped on request; the state is saved";

/// Throws std::invalid_argument unless `state` was made by `solver` for these vector lengths,
/// this many scalars and this volume.
void check_solver_state(const SolverState& state, const std::string& solver, const std::vector<std::size_t>& vector_lengths,
                        std::size_t scalars, const VolumeLayout& layout);

/// One file: a JSON line (the state's description and `run`, what the caller needs to check that a
/// continuation is the same run) followed by the raw float32 vectors. Written atomically.
void write_solver_state(const SolverSnapshot& state, const nlohmann::json& run, const std::filesystem::path& file);
/// Throws InputError naming the file on anything malformed or truncated.
SolverState read_solver_state(const std::filesystem::path& file, nlohmann::json& run);

}  // namespace ctk

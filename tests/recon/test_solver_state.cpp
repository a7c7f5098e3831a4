// A solver stopped on request and continued from its saved state (through the file) computes what
// the uninterrupted run computes; a damaged state file is refused, naming it.
#include <gtest/gtest.h>

#include <fstream>

#include "../test_support.hpp"
#include "ctk/core/error.hpp"
#include "ctk/geom/trajectory.hpp"
#include "ctk/proj/joseph_operator.hpp"
#include "ctk/recon/sirt.hpp"
#include "ctk/recon/solver_state.hpp"
#include "ctk/recon/wls_cg.hpp"

namespace ctk {
namespace {

struct SmallProblem {
  VolumeLayout layout = VolumeLayout::centred({24, 24, 24}, Eigen::Vector3d::Constant(1.0));
  Detector detector{32, 32, 1.5, 1.5};
  std::vector<ProjectionMatrix> views;
  ProjectionStack b, weights;

  SmallProblem() {
    const Intrinsics K = Intrinsics::from_setup(600, detector, detector.centre_px());
    for (const auto& R : circular_rotations(Eigen::Vector3d::UnitZ(), 20, 0.0, 2 * M_PI))
      views.push_back(ProjectionMatrix::compose(
          K, make_rigid(rotation_looking_along(R * Eigen::Vector3d::UnitX()), Eigen::Vector3d(0, 0, 400))));
    Volume truth(layout);
    for (int k = 6; k < 18; ++k)
      for (int j = 4; j < 16; ++j)
        for (int i = 8; i < 20; ++i) truth.at(i, j, k) = 0.02f + 0.001f * static_cast<float>(i + 2 * j);
    b = ProjectionStack(static_cast<int>(views.size()), detector.rows, detector.cols);
    JosephProjector().forward(truth, views, b);
    weights = b;
    for (float& w : weights.data) w = 1.0f / (1.0f + w);
  }
  JosephOperator projection() const { return {views, layout, detector.rows, detector.cols}; }
};

// Runs `solve` once whole and once stopped after `stop_after` iterations, saved to a file, read
// back and continued; returns the largest difference relative to the largest voxel.
template <typename Solve>
double continued_difference(const SmallProblem& p, int stop_after, const Solve& solve) {
  Volume whole(p.layout), continued(p.layout);
  solve(whole, nullptr);

  const auto file = testing::scratch_dir() / "state";
  int done = 0;
  Checkpointing first;
  first.stop_requested = [&] { return ++done == stop_after; };
  first.save = [&](const SolverSnapshot& s) { write_solver_state(s, {{"case", 1}}, file); };
  const SolverReport stopped = solve(continued, &first);
  EXPECT_EQ(stopped.stop_reason, kStoppedOnRequest);

  nlohmann::json run;
  SolverState state = read_solver_state(file, run);
  EXPECT_EQ(run, nlohmann::json({{"case", 1}}));
  EXPECT_EQ(state.iteration, stop_after);
  Checkpointing second;
  second.resume = &state;
  Volume fresh(p.layout);  // the state carries the iterate
  const SolverReport report = solve(fresh, &second);
  EXPECT_NE(report.stop_reason, kStoppedOnRequest);
  float peak = 0, worst = 0;
  for (std::size_t i = 0; i < whole.data.size(); ++i) {
    peak = std::max(peak, std::abs(whole.data[i]));
    worst = std::max(worst, std::abs(whole.data[i] - fresh.data[i]));
  }
  return worst / peak;
}

TEST(SolverState, WlsCgContinuedFromItsSavedStateEqualsTheUninterruptedRun) {
  const SmallProblem p;
  const JosephOperator A = p.projection();
  for (const CgPreconditioner preconditioner : {CgPreconditioner::none, CgPreconditioner::diagonal}) {
    WlsOptions o;
    o.iterations = 12;
    o.tolerance = 0;
    o.lambda = 0.5;
    o.regulariser = Regulariser::gradient;
    o.preconditioner = preconditioner;
    const double difference = continued_difference(
        p, 5, [&](Volume& x, const Checkpointing* c) { return solve_wls_cg(A, p.b, &p.weights, x, o, {}, c); });
    EXPECT_LE(difference, 1e-6) << to_string(preconditioner);
  }
}

TEST(SolverState, APlainCgStateDoesNotContinueAPreconditionedRun) {
  const SmallProblem p;
  const JosephOperator A = p.projection();
  const auto file = testing::scratch_dir() / "state";
  WlsOptions o;
  o.iterations = 6;
  int done = 0;
  Checkpointing first;
  first.stop_requested = [&] { return ++done == 3; };
  first.save = [&](const SolverSnapshot& s) { write_solver_state(s, {}, file); };
  Volume x(p.layout);
  solve_wls_cg(A, p.b, &p.weights, x, o, {}, &first);
  nlohmann::json run;
  SolverState state = read_solver_state(file, run);
  Checkpointing resume;
  resume.resume = &state;
  o.preconditioner = CgPreconditioner::diagonal;
  EXPECT_THROW(solve_wls_cg(A, p.b, &p.weights, x, o, {}, &resume), std::invalid_argument);
}

TEST(SolverState, SirtContinuedFromItsSavedStateEqualsTheUninterruptedRun) {
  const SmallProblem p;
  const JosephOperator A = p.projection();
  const double difference = continued_difference(p, 7, [&](Volume& x, const Checkpointing* c) {
    return solve_sirt(A, p.b, x, {15, 1.0, true}, {}, c);
  });
  EXPECT_LE(difference, 1e-6);
}

// Truncated, a bit flipped (the 2.5e36 voxel a flipped exponent bit made was resumed before the
// checksum), another format, another solver's: each refused.
TEST(SolverState, ADamagedOrForeignStateIsRefusedNamingTheFile) {
  const SmallProblem p;
  const auto dir = testing::scratch_dir();
  Volume x(p.layout);
  int done = 0;
  Checkpointing c;
  c.stop_requested = [&] { return ++done == 2; };
  c.save = [&](const SolverSnapshot& s) { write_solver_state(s, {}, dir / "state"); };
  solve_sirt(p.projection(), p.b, x, {5, 1.0, true}, {}, &c);
  const auto size = std::filesystem::file_size(dir / "state");
  std::filesystem::copy_file(dir / "state", dir / "cut");
  std::filesystem::resize_file(dir / "cut", size - 4);
  nlohmann::json run;
  try {
    read_solver_state(dir / "cut", run);
    FAIL() << "a truncated state was read";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("cut"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("truncated"), std::string::npos) << e.what();
  }
  // One flipped bit, in a voxel or in the header's description of the run: refused, naming the checksum.
  const auto header = [&] {
    std::ifstream in(dir / "state");
    std::string line;
    std::getline(in, line);
    return line.size() + 1;
  }();
  for (const std::uintmax_t at : {static_cast<std::uintmax_t>(header + 17), static_cast<std::uintmax_t>(header / 2)}) {
    std::filesystem::copy_file(dir / "state", dir / "flipped", std::filesystem::copy_options::overwrite_existing);
    std::fstream f(dir / "flipped", std::ios::in | std::ios::out | std::ios::binary);
    f.seekg(static_cast<std::streamoff>(at));
    char byte = 0;
    f.get(byte);
    if (at < header && (byte == '"' || byte == '\\' || byte == '{' || byte == '}' || byte == ':' || byte == ',')) continue;
    f.seekp(static_cast<std::streamoff>(at));
    f.put(static_cast<char>(byte ^ (at < header ? 0x01 : 0x40)));
    f.close();
    try {
      read_solver_state(dir / "flipped", run);
      FAIL() << "a state with a flipped bit at byte " << at << " was read";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("flipped"), std::string::npos) << e.what();
    }
  }
  std::ofstream(dir / "text") << "{\"format\": \"something-else\"}\n";
  EXPECT_THROW(read_solver_state(dir / "text", run), InputError);
  // A SIRT state does not continue a CG run.
  SolverState sirt_state = read_solver_state(dir / "state", run);
  Checkpointing resume;
  resume.resume = &sirt_state;
  Volume y(p.layout);
  WlsOptions o;
  o.iterations = 3;
  EXPECT_THROW(solve_wls_cg(p.projection(), p.b, nullptr, y, o, {}, &resume), std::invalid_argument);
}

}  // namespace
}  // namespace ctk

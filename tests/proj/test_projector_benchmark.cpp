// The projector benchmark as ctk bench runs it: every direction of both trajectories measured,
// the fast projector agreeing with the reference on the reference's views, the reference's time
// scaled per view, every run kept; its options check themselves.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "../test_support.hpp"
#include "ctk/proj/joseph_projector.hpp"
#include "ctk/proj/projector_benchmark.hpp"

namespace ctk {
namespace {

TEST(ProjectorBenchmark, MeasuresBothTrajectoriesAgainstTheReference) {
  ProjectorBenchmarkOptions o;
  o.scale = 16;
  o.views = 8;
  o.reference_views = 2;
  o.repeat = 2;
  std::vector<std::string> lines;
  const ProjectorBenchmark b = run_projector_benchmark(o, [&](const std::string& line) { lines.push_back(line); });
  const nlohmann::json& r = b.report;
  for (const nlohmann::json* d : {&r["forward"], &r["back"], &r["spherical"]["forward"], &r["spherical"]["back"]}) {
    EXPECT_LT((*d)["relative_difference_to_reference"].get<double>(), 1e-5) << d->dump();
    EXPECT_EQ((*d)["fast_seconds_runs"].size(), 2u);
    EXPECT_EQ((*d)["reference_views_measured"], 2);
    // The reference's time over its 2 views, scaled to the 8.
    EXPECT_NEAR((*d)["reference_seconds"].get<double>(), 4 * (*d)["reference_seconds_measured"].get<double>(), 1e-12);
    EXPECT_NEAR((*d)["speedup"].get<double>(), (*d)["reference_seconds"].get<double>() / (*d)["fast_seconds"].get<double>(),
                1e-9);
  }
  EXPECT_EQ(r["simd"]["target"], JosephProjector::simd_target());
  EXPECT_EQ(r["problem"]["views"], 8);
  EXPECT_NE(b.brief().find("spherical forward"), std::string::npos) << b.brief();
  ASSERT_GE(lines.size(), 8u);  // each trajectory's heading and column names, then one line per direction
  EXPECT_NE(lines[1].find("circular"), std::string::npos) << lines[1];
}

TEST(OptionsValidation, ProjectorBenchmarkOptions) {
  EXPECT_NO_THROW(ProjectorBenchmarkOptions{}.validate());
  testing::expect_option_refused(
      ProjectorBenchmarkOptions{}, [](auto& o) { o.views = 0; }, "ProjectorBenchmarkOptions.views");
  testing::expect_option_refused(
      ProjectorBenchmarkOptions{}, [](auto& o) { o.reference_views = 0; }, "ProjectorBenchmarkOptions.reference_views");
  testing::expect_option_refused(
      ProjectorBenchmarkOptions{}, [](auto& o) { o.scale = 0; }, "ProjectorBenchmarkOptions.scale");
  testing::expect_option_refused(
      ProjectorBenchmarkOptions{}, [](auto& o) { o.threads = -1; }, "ProjectorBenchmarkOptions.threads");
  testing::expect_option_refused(
      ProjectorBenchmarkOptions{}, [](auto& o) { o.repeat = 0; }, "ProjectorBenchmarkOptions.repeat");
  testing::expect_option_refused(
      ProjectorBenchmarkOptions{}, [](auto& o) { o.simd = "AVX9"; }, "ProjectorBenchmarkOptions.simd");
}

}  // namespace
}  // namespace ctk

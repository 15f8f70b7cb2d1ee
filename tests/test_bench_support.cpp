// The benchmark suite's scene builders (bench/bench_support.hpp): the enlarged
// boards hold exactly the requested particles, and the check values the
// benchmarks report are deterministic (otherwise they could not reveal a
// change of the physics).
#include "bench/bench_support.hpp"
#include "studies/jobs.hpp"

#include <gtest/gtest.h>

#include <cmath>

namespace gapflow::bench {
namespace {

TEST(BenchSupport, BoardsHoldEveryBenchmarkedCount) {
  const auto file = source_path(kPaperMedium);
  EXPECT_EQ(board_for(file, 500), std::vector<std::string>{"particles.count=500"});  // the paper's board as is
  double previous_width = 0;
  for (int count : {2000, 5000, 10000, 20000}) {
    const std::vector<std::string> overrides = board_for(file, count);
    const CompiledScenario sc = compile_with(file, overrides);
    EXPECT_EQ(static_cast<int>(sc.particles.size()), count);
    EXPECT_GT(sc.def.plane.width_mm, previous_width) << "the board widens with the count";
    previous_width = sc.def.plane.width_mm;
    EXPECT_EQ(board_for(file, count), overrides) << "deterministic labels";
  }
}

TEST(BenchSupport, CheckValuesAreDeterministic) {
  auto state_after = [](long steps) {
    FlowingHopper hopper(source_path(kPaperMedium), {"particles.count=150"}, ModelKind::box2d);
    hopper.advance(steps);
    return positions_hash(hopper.positions());
  };
  const double h = state_after(40);
  EXPECT_EQ(h, state_after(40));
  EXPECT_NE(h, state_after(41));
  // The hash is a 32-bit integer: exact as a Google Benchmark (double) counter.
  EXPECT_EQ(h, std::floor(h));
  EXPECT_LT(h, 4294967296.0);
}

TEST(BenchSupport, ThroughputStudyExpandsToShortRuns) {
  const std::vector<Job> jobs = expand_jobs(load_study(source_path("bench/study_throughput.toml")));
  ASSERT_EQ(jobs.size(), 16u);
  for (const Job& j : jobs) EXPECT_EQ(j.model, ModelKind::box2d);
}

}  // namespace
}  // namespace gapflow::bench

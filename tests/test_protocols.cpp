// Clog-breaking and re-injection protocols.
#include "models/registry.hpp"
#include "common/protocols.hpp"
#include "common/vec2_math.hpp"
#include "tests/test_support.hpp"

#include <gtest/gtest.h>

using namespace gapflow;
using gapflow::testing::compile_file;

namespace {
const char* kMedium = "scenarios/paper/no_obstruction_medium.toml";
const std::vector<std::string> kNarrowNoShaking = {"particles.count=300", "bottleneck.gap_mm=19.4",
                                                   "shaking.walls.enabled=false", "run.end=time_limit",
                                                   "run.time_limit_s=12", "run.stop_after_no_flow_s=0"};
std::vector<std::string> with(std::vector<std::string> v, const std::string& extra) {
  v.push_back(extra);
  return v;
}
}  // namespace

TEST(Protocols, LocalPerturbationBreaksClogsThatWouldBePermanent) {
  const RunRecord plain = run_model(compile_file(kMedium, kNarrowNoShaking), ModelKind::box2d);
  const RunRecord local =
      run_model(compile_file(kMedium, with(kNarrowNoShaking, "protocol.clog_breaking=local_perturbation")),
                ModelKind::box2d);
  EXPECT_EQ(plain.perturbations, 0);
  EXPECT_GE(local.perturbations, 3);
  EXPECT_GT(local.passed, plain.passed + 20) << "clogs broken by the protocol let more through";
  EXPECT_GE(local.avalanches.size(), 4u);
  EXPECT_EQ(local.escaped, 0);
  EXPECT_EQ(local.max_conservation_error, 0);
}

TEST(Protocols, RefillBreaksClogsAndKeepsEveryParticle) {
  const RunRecord r = run_model(compile_file(kMedium, with(kNarrowNoShaking, "protocol.clog_breaking=refill")),
                                ModelKind::box2d);
  EXPECT_GE(r.perturbations, 2);
  EXPECT_GE(r.avalanches.size(), 3u);
  EXPECT_EQ(r.escaped, 0);
  EXPECT_EQ(r.max_conservation_error, 0);
}

TEST(Protocols, ReinjectionGivesMoreCrossingsThanParticlesAndConservesThem) {
  const RunRecord r = run_model(compile_file(kMedium, {"particles.count=150", "bottleneck.gap_mm=40",
                                                       "protocol.reinject_passed=true", "run.end=time_limit",
                                                       "run.time_limit_s=6"}),
                                ModelKind::box2d);
  EXPECT_GT(r.passed, 2 * r.particles);
  EXPECT_GT(r.reinjected, r.particles);
  EXPECT_LE(r.passed - r.reinjected, r.particles);
  EXPECT_EQ(r.escaped, 0);
  EXPECT_EQ(r.max_conservation_error, 0);
  EXPECT_FALSE(r.j_paper.has_value()) << "the paper's J needs one complete emptying";
  EXPECT_TRUE(r.j_flowing.has_value());
}

TEST(Protocols, GapBlockersAreThoseWithALineOfSightToTheGapCentre) {
  const CompiledScenario sc = compile_file(kMedium, {"particles.count=3", "particles.size_scatter=0"});
  ClogProtocol p(sc);
  const double d = sc.nominal_diameter;
  // Particle 0 sits above the gap centre, particle 1 right behind it (hidden), particle 2 far away.
  const std::vector<ActiveParticle> board = {{0, {0.0, 0.6 * d}}, {1, {0.0, 1.7 * d}}, {2, {0.0, 20 * d}}};
  EXPECT_EQ(p.gap_blockers(board), std::vector<int>{0});
}

TEST(Protocols, InjectionSitesAreFreeAndOnTheBoard) {
  const CompiledScenario sc = compile_file(kMedium, {"particles.count=400"});
  ClogProtocol p(sc);
  std::vector<ActiveParticle> board;
  for (int i = 0; i < 400; ++i) board.push_back({i, sc.particles[static_cast<size_t>(i)].position});
  const std::vector<Vec2> sites = p.sites_on_top(board, 60);
  ASSERT_EQ(sites.size(), 60u);
  const double r_max = sc.nominal_diameter * 1.05 / 2;
  for (size_t i = 0; i < sites.size(); ++i) {
    EXPECT_TRUE(fits_on_board(sc, sites[i], r_max));
    for (const ActiveParticle& b : board) EXPECT_GE(length(b.position - sites[i]), 2 * r_max);
    for (size_t j = i + 1; j < sites.size(); ++j) EXPECT_GE(length(sites[j] - sites[i]), 2 * r_max);
  }
}

// Measurement from crossings: avalanches, clogs, censoring, flow rates.
#include "common/measurement.hpp"
#include "common/statistics.hpp"
#include "tests/test_support.hpp"

#include <gtest/gtest.h>

#include <cmath>

using namespace gapflow;

namespace {
std::vector<Crossing> at(std::initializer_list<double> times) {
  std::vector<Crossing> c;
  int id = 0;
  for (double t : times) c.push_back({id++, t, 0.0});
  return c;
}
}  // namespace

TEST(SegmentFlow, SplitsAvalanchesAtClogsAndFlagsTheFirstAndTheCensored) {
  std::vector<Avalanche> av;
  std::vector<Clog> cl;
  // flow, 2 s clog, flow, then the run ends 0.2 s after the last crossing (still flowing)
  segment_flow(at({0.1, 0.2, 0.3, 2.3, 2.4}), 1.0, 2.6, av, cl);
  ASSERT_EQ(av.size(), 2u);
  EXPECT_EQ(av[0].size, 3);
  EXPECT_TRUE(av[0].first);
  EXPECT_FALSE(av[0].censored);
  EXPECT_EQ(av[1].size, 2);
  EXPECT_FALSE(av[1].first);
  EXPECT_TRUE(av[1].censored);
  ASSERT_EQ(cl.size(), 1u);
  EXPECT_DOUBLE_EQ(cl[0].t_start, 0.3);
  EXPECT_DOUBLE_EQ(cl[0].duration, 2.0);
  EXPECT_FALSE(cl[0].censored);
}

TEST(SegmentFlow, ARunEndingInAClogCompletesTheAvalancheAndCensorsTheClog) {
  std::vector<Avalanche> av;
  std::vector<Clog> cl;
  segment_flow(at({0.1, 0.2}), 1.0, 10.0, av, cl);
  ASSERT_EQ(av.size(), 1u);
  EXPECT_FALSE(av[0].censored);
  ASSERT_EQ(cl.size(), 1u);
  EXPECT_TRUE(cl[0].censored);
  EXPECT_DOUBLE_EQ(cl[0].duration, 9.8);
}

TEST(SegmentFlow, NothingPassingIsOneCensoredClogFromRelease) {
  std::vector<Avalanche> av;
  std::vector<Clog> cl;
  segment_flow({}, 1.0, 5.0, av, cl);
  EXPECT_TRUE(av.empty());
  ASSERT_EQ(cl.size(), 1u);
  EXPECT_DOUBLE_EQ(cl[0].t_start, 0.0);
  EXPECT_TRUE(cl[0].censored);
}

TEST(Statistics, StudentIntervalMatchesTables) {
  EXPECT_NEAR(student_t_975(1), 12.706, 1e-3);
  EXPECT_NEAR(student_t_975(19), 2.093, 1e-3);
  EXPECT_NEAR(student_t_975(60), 2.0003, 1e-3);
  EXPECT_NEAR(student_t_975(1000), 1.9623, 1e-3);
  const Summary s = summarize({1, 2, 3, 4, 5});
  EXPECT_DOUBLE_EQ(s.mean, 3.0);
  EXPECT_NEAR(s.sd, 1.5811388, 1e-6);
  EXPECT_NEAR(s.ci95_half, 2.7764 * 1.5811388 / std::sqrt(5.0), 1e-4);
}

TEST(GapMonitor, CountsACrossingOnceWithInterpolatedTimeAndFlagsCrossingsBesideTheGap) {
  const CompiledScenario sc = gapflow::testing::compile_file(
      "scenarios/paper/no_obstruction_medium.toml", {"particles.count=3"});
  GapMonitor m(sc);
  // particle 0 goes from y = +1 mm to y = -1 mm between t = 0.1 and 0.2: crossing at 0.15
  m.observe(0, {0.0, 0.001}, 0.1);
  m.observe(1, {0.0, 0.05}, 0.1);
  m.observe(2, {0.0, 0.05}, 0.1);
  m.end_step(0.1);
  EXPECT_EQ(m.observe(0, {0.0, -0.001}, 0.2), ParticleFate::passed_keep);
  // particle 1 jumps across the gap line beside the gap: through a wall
  EXPECT_EQ(m.observe(1, {0.05, -0.001}, 0.2), ParticleFate::escaped);
  m.observe(2, {0.0, 0.05}, 0.2);
  m.end_step(0.2);
  EXPECT_EQ(m.observe(0, {0.0, -0.1}, 0.3), ParticleFate::passed_retire);
  m.observe(2, {0.0, 0.05}, 0.3);
  m.end_step(0.3);
  ASSERT_EQ(m.crossings().size(), 1u);
  EXPECT_NEAR(m.crossings()[0].t, 0.15, 1e-12);
  EXPECT_EQ(m.passed(), 1);
  EXPECT_EQ(m.escaped(), 1);
  EXPECT_EQ(m.inside(), 1);
  RunRecord r;
  m.finish(0.3, EndReason::time_limit, r);
  EXPECT_EQ(r.max_conservation_error, 0);
}

// Where a clog formed: at the step that makes a quiet period a clog, the distance
// from the gap centre to the nearest particle on the board. First an arch at the
// gap (a particle 0.6 d above the gap centre), then, after a crossing, a quiet
// period with the mouth empty (nearest particle 10 d up).
TEST(GapMonitor, LocatesEachClogByTheNearestParticleToTheGap) {
  const CompiledScenario sc = gapflow::testing::compile_file(
      "scenarios/paper/no_obstruction_medium.toml", {"particles.count=3", "run.clog_timeout_s=1"});
  const double d = sc.nominal_diameter;
  GapMonitor m(sc);
  double t = 0;
  auto hold = [&](Vec2 p0, Vec2 p1, Vec2 p2, double until) {
    for (; t < until - 1e-9;) {
      t += 0.1;
      m.observe(0, p0, t);
      m.observe(1, p1, t);
      m.observe(2, p2, t);
      m.end_step(t);
    }
  };
  hold({0.0, 0.6 * d}, {0.0, 3 * d}, {0.0, 12 * d}, 1.5);      // clog from release, arch at the gap
  hold({0.0, -0.5 * d}, {0.0, 10 * d}, {0.0, 12 * d}, 1.6);    // particle 0 crosses at ~1.55 s
  hold({0.0, -0.5 * d}, {6 * d, 8 * d}, {0.0, 12 * d}, 3.0);   // quiet again, mouth empty (10 d)
  hold({0.0, -0.5 * d}, {0.0, 4 * d}, {0.0, 12 * d}, 4.0);     // later, still quiet: not the front
  hold({0.0, -0.5 * d}, {0.0, -0.5 * d}, {0.0, 12 * d}, 4.1);  // particle 1 crosses: clog broken
  RunRecord r;
  m.finish(t, EndReason::time_limit, r);
  ASSERT_EQ(r.clogs.size(), 2u);
  ASSERT_TRUE(r.clogs[0].front_m);
  EXPECT_NEAR(*r.clogs[0].front_m, 0.6 * d, 1e-12) << "positions at detection (t = 1.0 s)";
  EXPECT_TRUE(clog_at_gap(*r.clogs[0].front_m, sc.gap, d));
  ASSERT_TRUE(r.clogs[1].front_m);
  EXPECT_NEAR(*r.clogs[1].front_m, 10 * d, 1e-12) << "detected 1 s after the crossing (2.55 s), before particle 1 moved on";
  EXPECT_FALSE(clog_at_gap(*r.clogs[1].front_m, sc.gap, d));
}

TEST(GapMonitor, AParticleThatVanishesBreaksConservation) {
  const CompiledScenario sc = gapflow::testing::compile_file(
      "scenarios/paper/no_obstruction_medium.toml", {"particles.count=2"});
  GapMonitor m(sc);
  m.observe(0, {0.0, 0.05}, 0.1);  // particle 1 is not reported: lost by the engine
  m.end_step(0.1);
  RunRecord r;
  m.finish(0.1, EndReason::time_limit, r);
  EXPECT_EQ(r.max_conservation_error, 1);
}

// J_paper = N/T needs a board that emptied; run.stranded_max particles may stay behind
// (e.g. balanced on a V's flat face), whatever ended the run, and the wait after the
// last crossing is then not a clog.
TEST(GapMonitor, StrandedParticlesCountAsEmptiedWhenAllowed) {
  auto record = [](std::vector<std::string> set, EndReason reason) {
    set.push_back("particles.count=3");
    const CompiledScenario sc = gapflow::testing::compile_file("scenarios/paper/no_obstruction_medium.toml", set);
    GapMonitor m(sc);
    for (int i = 0; i < 3; ++i) m.observe(i, {0.0, 0.001}, 0.1);
    m.end_step(0.1);
    m.observe(0, {0.0, -0.001}, 0.2);  // crossing at 0.15
    m.observe(1, {0.0, -0.001}, 0.2);
    m.observe(2, {0.0, 0.05}, 0.2);   // stays behind
    m.end_step(0.2);
    RunRecord r;
    m.finish(40.0, reason, r);
    return r;
  };
  const RunRecord strict = record({"run.stranded_max=0"}, EndReason::permanent_clog);
  EXPECT_FALSE(strict.j_paper) << "none may stay behind";
  EXPECT_EQ(strict.regime, Regime::clogged);
  ASSERT_EQ(strict.clogs.size(), 1u);
  EXPECT_TRUE(strict.clogs.back().censored);
  for (EndReason reason : {EndReason::permanent_clog, EndReason::time_limit}) {
    const RunRecord allowed = record({"run.stranded_max=1"}, reason);
    ASSERT_TRUE(allowed.j_paper);
    EXPECT_NEAR(*allowed.j_paper, 2 / 0.15, 1e-9) << "N passed / time of the last crossing";
    EXPECT_TRUE(allowed.clogs.empty()) << "the wait after an emptied board is not a clog";
    EXPECT_EQ(allowed.regime, Regime::continuous);
    ASSERT_EQ(allowed.avalanches.size(), 1u);
    EXPECT_TRUE(allowed.avalanches.back().censored) << "ended by the end of the discharge, not by a clog";
  }
  EXPECT_FALSE(record({"run.stranded_max=0"}, EndReason::time_limit).j_paper);
}

// The front of a stopped flow (common/clog_front.hpp) and where the gap monitor
// locates a clog by it (clog_site, common/measurement.hpp): hand-placed discs.
#include "common/clog_front.hpp"
#include "common/measurement.hpp"
#include "common/vec2_math.hpp"
#include "tests/test_support.hpp"

#include <gtest/gtest.h>

#include <cmath>

using namespace gapflow;
using gapflow::testing::compile_file;

namespace {

const ShakeOffsets kAtRest{};

// The A of the paper's scenario at D = 5 mm (to its centroid): its flat base lies
// 0.67 mm above the gap line, right over the gap centre. Nothing shaken.
CompiledScenario close_a() {
  return compile_file("scenarios/paper/a_obstruction.toml",
                      {"obstruction.distance_mm=5", "particles.count=4", "particles.size_scatter=0",
                       "shaking.walls.enabled=false", "shaking.obstruction.enabled=false"});
}

double tolerance(const CompiledScenario& sc) { return kBoundaryContactTolerance_d * sc.nominal_diameter; }

// A two-disc arch in the A's right passage: disc 0 rests on the A's right flank, 2 mm up
// from its lower right corner; disc 1 touches disc 0 and the right bottleneck wall.
std::vector<BoardDisc> arch_beside_right_flank(const CompiledScenario& sc) {
  const double r = sc.nominal_diameter / 2;
  const std::vector<Vec2>& v = sc.obstruction.polygon.vertices;
  Vec2 corner = v[0], apex = v[0];
  for (Vec2 p : v) {
    if (p.y < corner.y || (p.y == corner.y && p.x > corner.x)) corner = p;  // lowest, then rightmost
    if (p.y > apex.y) apex = p;
  }
  const Vec2 up = (1 / length(apex - corner)) * (apex - corner);
  const Vec2 outward{-up.y, up.x};  // perpendicular to the flank, pointing away from the A (+x)
  const Vec2 on_flank = corner + 0.002 * up + (r + 1e-6) * (outward.x > 0 ? outward : -1 * outward);
  // Disc 1 at 2r from disc 0, turned up by the angle at which it just touches the wall (bisection:
  // turning up moves it away from the wall, which leans outward).
  auto next_to = [&](double angle) { return on_flank + 2 * r * Vec2{std::cos(angle), std::sin(angle)}; };
  double lo = -1.0, hi = 1.4;
  for (int i = 0; i < 60; ++i) {
    const double mid = (lo + hi) / 2;
    (clearance_to_bottleneck_walls(sc, next_to(mid)) < r ? lo : hi) = mid;
  }
  return {{0, on_flank, r}, {1, next_to(hi), r}};
}

}  // namespace

TEST(ClogFront, ADiscBehindAnotherOrBehindTheObstructionIsNotSeen) {
  const CompiledScenario sc = compile_file("scenarios/paper/cylinder.toml",
                                           {"obstruction.distance_mm=70", "particles.count=4"});
  const double r = sc.nominal_diameter / 2;
  const Circle& c = sc.obstruction.circle;
  const std::vector<BoardDisc> discs = {
      {0, {-0.01, 0.01}, r},                                           // left of the gap's axis
      {1, {-0.02, 0.02}, r},                                           // right behind disc 0, on the same ray
      {2, {c.centre.x, c.centre.y + c.radius + r}, r},                 // resting on top of the cylinder
      {3, {c.centre.x + c.radius + r, sc.obstruction.nearest_y}, r},  // beside its lowest point
  };
  EXPECT_EQ(visible_from(sc.obstruction, discs, {0, 0}), (std::vector<int>{0, 3}));
  EXPECT_EQ(visible_from(ObstructionGeometry{}, discs, {0, 0}), (std::vector<int>{0, 2, 3}))
      << "without the obstruction only disc 1 is hidden (by disc 0)";
  EXPECT_EQ(visible_from_gap(sc, sc.obstruction, discs), (std::vector<int>{0, 1, 3}))
      << "the gap's left end sees disc 1 past disc 0; no point of the gap line sees past the cylinder to disc 2";
}

// The scan for occluders stops at |p - eye| + r_max: a disc a little further from the eye
// than p can still cut the segment near p's end (the bound must include its radius).
TEST(ClogFront, AnOccluderFurtherFromTheEyeThanTheDiscItHidesIsFound) {
  const double r = 0.004;
  const std::vector<BoardDisc> discs = {{0, {0.0, 0.05}, r}, {1, {0.9 * r, 0.05 + 0.1 * r}, r}};
  ASSERT_GT(length(discs[1].centre), length(discs[0].centre));
  // Each hides the other; a bound without r_max would miss disc 1 as disc 0's occluder.
  EXPECT_TRUE(visible_from(ObstructionGeometry{}, discs, {0, 0}).empty());
}

TEST(ClogFront, AnArchBesideACloseObstructionFacesTheGapsEndNotItsCentre) {
  const CompiledScenario sc = close_a();
  ASSERT_LT(sc.obstruction.nearest_y, 0.001) << "the A's base must hang over the gap centre";
  const std::vector<BoardDisc> arch = arch_beside_right_flank(sc);
  ASSERT_LE(clearance_to_bottleneck_walls(sc, arch[1].centre) - arch[1].radius, 1e-9) << "disc 1 on the wall";
  EXPECT_TRUE(visible_from(sc.obstruction, {arch[0]}, {0, 0}).empty()) << "the A hides the flank from the gap centre";
  EXPECT_EQ(visible_from_gap(sc, sc.obstruction, {arch[0]}), std::vector<int>{0}) << "the gap's right part sees it";
  EXPECT_TRUE(touches_obstruction(sc.obstruction, arch[0], tolerance(sc)));
  EXPECT_FALSE(touches_obstruction(sc.obstruction, arch[1], tolerance(sc)));
  EXPECT_TRUE(front_leans_on_obstruction(sc, arch, kAtRest)) << "obstruction - disc 0 - disc 1 - wall";
  EXPECT_FALSE(front_leans_on_obstruction(sc, {arch[0]}, kAtRest)) << "no chain to a wall";
}

// An arch across a narrow gap (three discs, wall to wall) whose middle disc touches the base
// of an A just above it: the arch rests on the obstruction but stands from wall to wall, so it
// is an arch across the gap. Without the right disc, the chain runs wall - disc - disc - A.
TEST(ClogFront, AnArchFromWallToWallIsAcrossTheGapEvenIfItTouchesTheObstruction) {
  const CompiledScenario probe = compile_file("scenarios/paper/a_obstruction.toml",
                                              {"bottleneck.gap_mm=19.4", "particles.count=4", "particles.size_scatter=0"});
  const double d = probe.nominal_diameter, r = d / 2;
  const double centroid_above_base = probe.obstruction.centroid.y - probe.obstruction.nearest_y;
  const CompiledScenario sc = compile_file(
      "scenarios/paper/a_obstruction.toml",
      {"bottleneck.gap_mm=19.4", "particles.count=4", "particles.size_scatter=0", "shaking.walls.enabled=false",
       "shaking.obstruction.enabled=false",
       "obstruction.distance_mm=" + std::to_string((1.05 * d + centroid_above_base) * 1e3)});
  ASSERT_NEAR(sc.obstruction.nearest_y, 1.05 * d, 1e-6);
  const std::vector<BoardDisc> arch = {{0, {-d, r}, r}, {1, {0.0, r}, r}, {2, {d, r}, r}};
  for (const BoardDisc& side : {arch[0], arch[2]})
    ASSERT_LE(clearance_to_bottleneck_walls(sc, side.centre) - r, tolerance(sc)) << "the side discs touch the walls";
  ASSERT_TRUE(touches_obstruction(sc.obstruction, arch[1], tolerance(sc)));
  EXPECT_FALSE(front_leans_on_obstruction(sc, arch, kAtRest));
  EXPECT_TRUE(front_leans_on_obstruction(sc, {arch[0], arch[1]}, kAtRest));
  // The right disc 0.05 d further right (against its wall): two arches, wall - disc - disc - A
  // and A... - disc - wall, that come close but do not touch: not one arch from wall to wall.
  std::vector<BoardDisc> apart = arch;
  apart[2].centre.x += 0.05 * d;
  EXPECT_TRUE(front_leans_on_obstruction(sc, apart, kAtRest));
}

// A shaken obstruction moves at 20 Hz, faster than the spheres on it can follow: it is taken
// where the schedule has it, and its reach widened by its displacement at that moment.
TEST(ClogFront, AShakenObstructionReachesAsFarAsItIsDisplaced) {
  const CompiledScenario sc = close_a();
  const double d = sc.nominal_diameter;
  std::vector<BoardDisc> arch = arch_beside_right_flank(sc);
  const Vec2 right{1, 0};
  for (BoardDisc& b : arch) b.centre = b.centre + 0.3 * d * right;  // the arch 0.3 d right: ~0.26 d off the flank
  ASSERT_LE(clearance_to_bottleneck_walls(sc, arch[1].centre) - arch[1].radius, 0.0) << "still on its wall";
  ASSERT_FALSE(touches_obstruction(sc.obstruction, arch[0], tolerance(sc)));
  EXPECT_FALSE(front_leans_on_obstruction(sc, arch, kAtRest)) << "at rest the flank is out of reach";
  ShakeOffsets toward{}, away{};
  toward.obstruction = 0.2 * d * right;
  away.obstruction = -0.2 * d * right;
  EXPECT_TRUE(front_leans_on_obstruction(sc, arch, toward)) << "moved 0.2 d toward the arch, reach 0.3 d";
  EXPECT_FALSE(front_leans_on_obstruction(sc, arch, away)) << "moved 0.2 d away: ~0.43 d off, reach 0.3 d";
}

// The gap monitor at the step that makes a quiet period a clog: the arch beside the A's right
// flank lies within W/2 + d of the gap centre, so the front distance alone would call the clog
// "at the gap"; the arch leans on the obstruction, so it is located there.
TEST(ClogFront, TheMonitorLocatesAnArchOnTheObstructionThereAndAnArchAcrossTheGapAtTheGap) {
  const CompiledScenario sc = close_a();
  const double d = sc.nominal_diameter;
  const std::vector<BoardDisc> arch = arch_beside_right_flank(sc);
  GapMonitor m(sc);
  double t = 0;
  for (; t < 1.5 - 1e-9;) {
    t += 0.1;
    m.observe(0, arch[0].centre, t);
    m.observe(1, arch[1].centre, t);
    for (int i = 2; i < 4; ++i) m.observe(i, {0.02 * (i - 2.5), 30 * d}, t);
    m.end_step(t);
  }
  RunRecord rec;
  m.finish(t, EndReason::time_limit, rec);
  ASSERT_EQ(rec.clogs.size(), 1u);
  const Clog& c = rec.clogs[0];
  ASSERT_TRUE(c.front_m && c.on_obstruction);
  EXPECT_TRUE(clog_at_gap(*c.front_m, sc.gap, d)) << "the front distance alone says: at the gap";
  EXPECT_TRUE(*c.on_obstruction);
  EXPECT_EQ(clog_site(c, sc.gap, d), ClogSite::obstruction);

  // A board without an obstruction: the arch is across the gap.
  const CompiledScenario open = compile_file("scenarios/paper/no_obstruction_medium.toml",
                                             {"particles.count=4", "particles.size_scatter=0"});
  GapMonitor m2(open);
  t = 0;
  for (; t < 1.5 - 1e-9;) {
    t += 0.1;
    m2.observe(0, {0.0, 0.6 * d}, t);
    for (int i = 1; i < 4; ++i) m2.observe(i, {0.02 * (i - 2), 30 * d}, t);
    m2.end_step(t);
  }
  RunRecord rec2;
  m2.finish(t, EndReason::time_limit, rec2);
  ASSERT_EQ(rec2.clogs.size(), 1u);
  ASSERT_TRUE(rec2.clogs[0].on_obstruction);
  EXPECT_FALSE(*rec2.clogs[0].on_obstruction);
  EXPECT_EQ(clog_site(rec2.clogs[0], open.gap, d), ClogSite::gap);
}

TEST(ClogFront, SiteFollowsWhatWasMeasured) {
  const double gap = 0.033, d = 0.00775;
  Clog c;
  EXPECT_FALSE(clog_site(c, gap, d)) << "no front measured: not located";
  c.front_m = 0.5 * d;
  EXPECT_EQ(clog_site(c, gap, d), ClogSite::gap) << "an older record (no on_obstruction): by its front alone";
  c.front_m = 10 * d;
  EXPECT_EQ(clog_site(c, gap, d), ClogSite::upstream);
  c.on_obstruction = false;
  EXPECT_EQ(clog_site(c, gap, d), ClogSite::upstream);
  c.on_obstruction = true;
  EXPECT_EQ(clog_site(c, gap, d), ClogSite::obstruction);
  c.front_m = 0.5 * d;
  EXPECT_EQ(clog_site(c, gap, d), ClogSite::obstruction) << "leaning on the obstruction wins over the front distance";
}

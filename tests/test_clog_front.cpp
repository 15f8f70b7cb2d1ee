// The front of a stopped flow (common/clog_front.hpp) and where the gap monitor
// locates a clog by it (clog_site, common/measurement.hpp): hand-placed discs.
#include "common/clog_front.hpp"
#include "common/measurement.hpp"
#include "common/vec2_math.hpp"
#include "tests/test_support.hpp"

#include <gtest/gtest.h>

using namespace gapflow;
using gapflow::testing::compile_file;

namespace {

// The A of the paper's scenario at D = 5 mm (to its centroid): its flat base lies
// 0.67 mm above the gap line, right over the gap centre. No shaking, so the contact
// tolerance is 0.1 d.
CompiledScenario close_a() {
  return compile_file("scenarios/paper/a_obstruction.toml",
                      {"obstruction.distance_mm=5", "particles.count=4", "particles.size_scatter=0",
                       "shaking.walls.enabled=false", "shaking.obstruction.enabled=false"});
}

// A disc of radius r resting `gap` (m) off the A's right flank, `along` (m) up the flank
// from its lower right corner.
Vec2 beside_right_flank(const CompiledScenario& sc, double r, double along, double gap) {
  const std::vector<Vec2>& v = sc.obstruction.polygon.vertices;
  Vec2 corner = v[0], apex = v[0];
  for (Vec2 p : v) {
    if (p.y < corner.y || (p.y == corner.y && p.x > corner.x)) corner = p;  // lowest, then rightmost
    if (p.y > apex.y) apex = p;
  }
  const Vec2 up = (1 / length(apex - corner)) * (apex - corner);
  const Vec2 out{-up.y, up.x};  // the flank's outward normal points right and up: rotate `up` clockwise
  const Vec2 normal = out.x > 0 ? out : Vec2{up.y, -up.x};
  return corner + along * up + (r + gap) * normal;
}

}  // namespace

TEST(ClogFront, ADiscBehindAnotherOrBehindTheObstructionIsNotSeen) {
  const CompiledScenario sc = compile_file("scenarios/paper/cylinder.toml",
                                           {"obstruction.distance_mm=70", "particles.count=4"});
  const double r = sc.nominal_diameter / 2;
  const Vec2 eye{0, 0};
  const Circle& c = sc.obstruction.circle;
  const std::vector<BoardDisc> discs = {
      {0, {-0.01, 0.01}, r},                         // left of the gap's axis, clear of the other rays
      {1, {-0.02, 0.02}, r},                         // right behind disc 0, on the same ray
      {2, {c.centre.x, c.centre.y + c.radius + 2 * r}, r},  // on top of the cylinder: hidden by it
      {3, {c.centre.x + c.radius + r, sc.obstruction.nearest_y}, r},  // beside its lowest point: seen past it
  };
  EXPECT_EQ(visible_from(sc.obstruction, discs, eye), (std::vector<int>{0, 3}));
  EXPECT_EQ(visible_from(ObstructionGeometry{}, discs, eye), (std::vector<int>{0, 2, 3}))
      << "without the obstruction only disc 1 is hidden (by disc 0)";
}

TEST(ClogFront, AnArchBesideACloseObstructionFacesTheGapsEndNotItsCentre) {
  const CompiledScenario sc = close_a();
  ASSERT_LT(sc.obstruction.nearest_y, 0.001) << "the A's base must hang over the gap centre";
  const double r = sc.nominal_diameter / 2;
  const BoardDisc on_flank{7, beside_right_flank(sc, r, 0.002, 0.0001 * r), r};
  const std::vector<BoardDisc> discs = {on_flank};
  EXPECT_TRUE(visible_from(sc.obstruction, discs, {0, 0}).empty()) << "the A hides the flank from the gap centre";
  EXPECT_EQ(visible_from_gap(sc, discs), std::vector<int>{7}) << "the gap's right part sees it";
  EXPECT_TRUE(touches_obstruction(sc.obstruction, on_flank, obstruction_contact_tolerance(sc)));
  const BoardDisc off_flank{8, beside_right_flank(sc, r, 0.002, 0.2 * sc.nominal_diameter), r};
  EXPECT_FALSE(touches_obstruction(sc.obstruction, off_flank, obstruction_contact_tolerance(sc)))
      << "0.2 d off is beyond the 0.1 d tolerance";
}

TEST(ClogFront, ShakingTheObstructionWidensTheContactToleranceByItsAmplitude) {
  const CompiledScenario still = close_a();
  const CompiledScenario shaken = compile_file(
      "scenarios/paper/a_obstruction.toml",
      {"obstruction.distance_mm=5", "shaking.obstruction.enabled=true", "shaking.obstruction.amplitude_mm=1"});
  EXPECT_NEAR(obstruction_contact_tolerance(still), 0.1 * still.nominal_diameter, 1e-15);
  EXPECT_NEAR(obstruction_contact_tolerance(shaken), 0.1 * shaken.nominal_diameter + 0.001, 1e-15);
}

// The gap monitor at the step that makes a quiet period a clog: particle 0 leans on the A's
// right flank within W/2 + d of the gap centre, so the front distance alone would call the
// clog "at the gap"; the front touches the obstruction, so it is located there.
TEST(ClogFront, TheMonitorLocatesAnArchOnTheObstructionThereAndAnArchAcrossTheGapAtTheGap) {
  const CompiledScenario sc = close_a();
  const double r = sc.nominal_diameter / 2, d = sc.nominal_diameter;
  GapMonitor m(sc);
  double t = 0;
  auto hold = [&](const std::vector<Vec2>& at, double until) {
    for (; t < until - 1e-9;) {
      t += 0.1;
      for (size_t i = 0; i < at.size(); ++i) m.observe(static_cast<int>(i), at[i], t);
      m.end_step(t);
    }
  };
  const Vec2 on_flank = beside_right_flank(sc, r, 0.002, 0.0001 * r);
  hold({on_flank, {0.0, 30 * d}, {0.1, 30 * d}, {-0.1, 30 * d}}, 1.5);
  RunRecord rec;
  m.finish(t, EndReason::time_limit, rec);
  ASSERT_EQ(rec.clogs.size(), 1u);
  const Clog& c = rec.clogs[0];
  ASSERT_TRUE(c.front_m && c.on_obstruction);
  EXPECT_TRUE(clog_at_gap(*c.front_m, sc.gap, d)) << "the front distance alone says: at the gap";
  EXPECT_TRUE(*c.on_obstruction);
  EXPECT_EQ(clog_site(c, sc.gap, d), ClogSite::obstruction);

  // The same board without an obstruction: the arch is across the gap.
  const CompiledScenario open = compile_file("scenarios/paper/no_obstruction_medium.toml",
                                             {"particles.count=4", "particles.size_scatter=0"});
  GapMonitor m2(open);
  t = 0;
  for (; t < 1.5 - 1e-9;) {
    t += 0.1;
    m2.observe(0, {0.0, 0.6 * d}, t);
    for (int i = 1; i < 4; ++i) m2.observe(i, {0.02 * i, 30 * d}, t);
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

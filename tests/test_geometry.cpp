// Compiled geometry: the gap, the walls, the obstruction position, the packing.
#include "common/units.hpp"
#include "common/vec2_math.hpp"
#include "tests/test_support.hpp"

#include <gtest/gtest.h>

#include <cmath>

using namespace gapflow;
using gapflow::testing::compile_file;

TEST(Geometry, GapBetweenWallTipsEqualsW) {
  for (double w : {12.0, 33.0, 50.5}) {
    const CompiledScenario c =
        compile_file("scenarios/paper/no_obstruction_medium.toml", {"bottleneck.gap_mm=" + std::to_string(w)});
    EXPECT_NEAR(c.right_tip.x - c.left_tip.x, w * 1e-3, 1e-12);
    // The tips are the narrowest points: every vertex of a bottleneck wall is at |x| >= W/2.
    for (Vec2 v : c.right_bottleneck_wall.vertices) EXPECT_GE(v.x, w * 1e-3 / 2 - 1e-12);
    for (Vec2 v : c.left_bottleneck_wall.vertices) EXPECT_LE(v.x, -w * 1e-3 / 2 + 1e-12);
  }
}

TEST(Geometry, BottleneckWallsMakeTheStatedAngleWithTheRetainingWalls) {
  const CompiledScenario c = compile_file("scenarios/paper/no_obstruction_medium.toml");
  const Vec2 top{c.channel_width / 2, c.funnel_height};
  const Vec2 along = top - c.right_tip;
  EXPECT_NEAR(std::atan2(along.x, along.y), deg_to_rad(30.0), 1e-12);  // angle to the +y retaining wall
}

TEST(Geometry, NinetyDegreesGivesAFlatBottomedSilo) {
  const CompiledScenario c =
      compile_file("scenarios/paper/no_obstruction_medium.toml", {"bottleneck.wall_angle_deg=90"});
  EXPECT_NEAR(c.funnel_height, 0.0, 1e-12);
  for (Vec2 v : c.right_bottleneck_wall.vertices) EXPECT_LE(v.y, 1e-12);  // the floor is the gap line
  EXPECT_NEAR(c.half_width_at(0.01), c.channel_width / 2, 1e-12);
}

TEST(Geometry, ObstructionSitsAtTheStatedDistance) {
  // centre reference: the centroid is D above the gap line.
  const CompiledScenario cyl = compile_file("scenarios/paper/cylinder.toml", {"obstruction.distance_mm=120"});
  EXPECT_NEAR(cyl.obstruction.circle.centre.y, 0.120, 1e-12);
  const CompiledScenario a = compile_file("scenarios/paper/a_obstruction.toml", {"obstruction.distance_mm=20"});
  EXPECT_NEAR(a.obstruction.centroid.y, 0.020, 1e-12);
  const CompiledScenario v = compile_file("scenarios/paper/v_obstruction.toml", {"obstruction.distance_mm=60"});
  EXPECT_NEAR(v.obstruction.centroid.y, 0.060, 1e-12);
  // nearest reference: the lowest point is D above the gap line.
  const CompiledScenario n = compile_file("scenarios/paper/cylinder.toml",
                                          {"obstruction.distance_mm=50", "obstruction.reference=nearest"});
  EXPECT_NEAR(n.obstruction.nearest_y, 0.050, 1e-12);
  EXPECT_NEAR(n.obstruction.circle.centre.y, 0.050 + 0.040, 1e-12);
  // V points at the gap, A away from it.
  double v_lowest_x = 1, a_top_x = 1, a_top = -1, v_low = 1;
  for (Vec2 p : v.obstruction.polygon.vertices)
    if (p.y < v_low) v_low = p.y, v_lowest_x = p.x;
  for (Vec2 p : a.obstruction.polygon.vertices)
    if (p.y > a_top) a_top = p.y, a_top_x = p.x;
  EXPECT_NEAR(v_lowest_x, 0.0, 1e-12);
  EXPECT_NEAR(a_top_x, 0.0, 1e-12);
}

TEST(Geometry, PaperMinimumDistancesMatchTheScenarioComments) {
  // Documented in scenarios/paper/*.toml: one particle diameter of clearance at
  // D_min = 66.9 mm (cylinder) and 4.3 mm (A, base on the gap line).
  const CompiledScenario cyl = compile_file("scenarios/paper/cylinder.toml", {"obstruction.distance_mm=66.92"});
  EXPECT_NEAR(obstruction_wall_clearance(cyl) / cyl.nominal_diameter, 1.0, 0.01);
  const CompiledScenario a = compile_file("scenarios/paper/a_obstruction.toml", {"obstruction.distance_mm=4.34"});
  EXPECT_NEAR(a.obstruction.nearest_y, 0.0, 1e-4);
  EXPECT_GT(obstruction_wall_clearance(a), a.nominal_diameter);
}

TEST(Geometry, PackingHasNoOverlapsAndStaysInsideTheWalls) {
  const CompiledScenario c = compile_file("scenarios/paper/cylinder.toml");
  ASSERT_EQ(c.particles.size(), 1551u);
  for (size_t i = 0; i < c.particles.size(); ++i) {
    const ParticleSeed& p = c.particles[i];
    const double r = p.diameter / 2;
    EXPECT_GE(p.position.y - r, c.barrier_y);
    EXPECT_LE(std::abs(p.position.x) + r, c.channel_width / 2);
    EXPECT_GE(clearance_to_bottleneck_walls(c, p.position), r);
    EXPECT_GE(length(p.position - c.obstruction.circle.centre), c.obstruction.circle.radius + r);
    for (size_t j = i + 1; j < c.particles.size(); ++j) {
      const double dist = length(p.position - c.particles[j].position);
      if (dist < 0.05) {
        ASSERT_GE(dist, r + c.particles[j].diameter / 2) << i << " overlaps " << j;
      }
    }
  }
}

TEST(Geometry, SizesFollowTheScatterAndSurviveAParameterChange) {
  const CompiledScenario a = compile_file("scenarios/paper/no_obstruction_medium.toml");
  const CompiledScenario b =
      compile_file("scenarios/paper/no_obstruction_medium.toml", {"bottleneck.gap_mm=40"});
  double lo = 1, hi = 0;
  for (size_t i = 0; i < a.particles.size(); ++i) {
    const double f = a.particles[i].diameter / a.nominal_diameter;
    lo = std::min(lo, f);
    hi = std::max(hi, f);
    EXPECT_EQ(a.particles[i].diameter, b.particles[i].diameter) << "common random numbers across a gap change";
  }
  EXPECT_GE(lo, 0.95);
  EXPECT_LE(hi, 1.05);
  EXPECT_LT(lo, 0.955);  // uniform +-5 %: 1551 draws reach the ends
  EXPECT_GT(hi, 1.045);
}

// The calibration effects (plane.lateral_tilt_deg, bottleneck.gap_offset_mm,
// particles.drag_per_s, particles.quadratic_drag_per_m, obstruction.corner_radius_mm),
// each alone against its analytic result in both models, and the rule that a new key
// at its default leaves every existing scenario hash (job key, stored result) as it was.
#include "common/scenario_loader.hpp"
#include "common/simulation.hpp"
#include "common/units.hpp"
#include "common/vec2_math.hpp"
#include "sim2d/session2d.hpp"
#include "sim3d/session3d.hpp"
#include "tests/test_support.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

using namespace gapflow;
using gapflow::testing::compile_file;
using gapflow::testing::compile_text;

namespace {

// One particle far from every wall, no settling; overrides "section.key=value".
const std::string kOneParticle = gapflow::testing::open_board_scenario("effects single particle", 1);

CompiledScenario one_particle(const std::vector<std::string>& overrides) { return compile_text(kOneParticle, overrides); }

const double kK = 0.4;  // I/(m r^2) of a solid sphere

// --- 2D helpers (lab units) ---------------------------------------------------
Vec2 velocity2d(const Session2D& s) {
  const World2D& w = s.world();
  const b2Vec2 v = w.particles[0]->GetLinearVelocity();
  return {w.scale.to_lab_velocity(v.x), w.scale.to_lab_velocity(v.y)};
}
void launch2d(Session2D& s, Vec2 position_m, Vec2 velocity_m_s) {
  World2D& w = s.world();
  s.set_barrier(false);
  w.particles[0]->SetTransform(w.to_engine(position_m), 0.0f);
  w.particles[0]->SetLinearVelocity(
      {static_cast<float>(w.scale.to_engine_velocity(velocity_m_s.x)),
       static_cast<float>(w.scale.to_engine_velocity(velocity_m_s.y))});
}
template <class S>
void run_for(S& s, double seconds) {
  const long n = std::lround(seconds / s.time_step());
  for (long i = 0; i < n; ++i) s.step();
}

// Acceleration across (+x) from the velocity change over [t1, t2].
double across_acceleration2d(const CompiledScenario& sc) {
  Session2D s(sc);
  launch2d(s, {0, 1.0}, {0, 0});
  run_for(s, 0.1);
  const double v1 = velocity2d(s).x;
  run_for(s, 0.3);
  return (velocity2d(s).x - v1) / 0.3;
}

}  // namespace

// ---------------------------------------------------------------- hashes

// Values computed with `gapflow check` on 02d739b, before these keys existed.
// The hashes of the committed stores' runs: made when the 3D step defaulted to 2 ms, which their
// study files now pin (README "The 3D model"); with the pin they must not move.
TEST(EffectKeys, DefaultsLeaveExistingScenarioHashesUnchanged) {
  const std::vector<std::string> pin = {"model.bullet.time_step_s=0.002"};
  EXPECT_EQ(compile_file("scenarios/paper/no_obstruction_medium.toml", pin).scenario_hash, 0xb0a8525188553fa4ull);
  EXPECT_EQ(compile_file("scenarios/paper/cylinder.toml", pin).scenario_hash, 0xc2675b6f7ca7d4b3ull);
  EXPECT_NE(compile_file("scenarios/paper/cylinder.toml").scenario_hash, 0xc2675b6f7ca7d4b3ull);  // 1 ms now
  const std::string text = canonical_toml(compile_file("scenarios/paper/cylinder.toml").def);
  for (const char* key : {"lateral_tilt_deg", "gap_offset_mm", "drag_per_s", "quadratic_drag_per_m", "corner_radius_mm"})
    EXPECT_EQ(text.find(key), std::string::npos) << key;
}

const std::vector<std::string> kRoundedA = {"obstruction.shape=\"A\"", "obstruction.distance_mm=50.0"};

TEST(EffectKeys, SetKeysChangeTheHashAndReadBack) {
  const std::vector<std::string> keys = {"plane.lateral_tilt_deg=2.5", "bottleneck.gap_offset_mm=-1.5",
                                         "particles.drag_per_s=3.0", "particles.quadratic_drag_per_m=4.0",
                                         "obstruction.corner_radius_mm=1.0"};
  const std::uint64_t plain = scenario_hash(parse_scenario(kOneParticle, "p.toml", kRoundedA).def);
  std::vector<std::string> all = kRoundedA;
  for (const std::string& k : keys) {
    std::vector<std::string> one = kRoundedA;
    one.push_back(k);
    EXPECT_NE(scenario_hash(parse_scenario(kOneParticle, "o.toml", one).def), plain) << k;
    all.push_back(k);
  }
  const LoadedScenario a = parse_scenario(kOneParticle, "a.toml", all);
  const LoadedScenario back = parse_scenario(canonical_toml(a.def), "back.toml");
  EXPECT_EQ(scenario_hash(back.def), scenario_hash(a.def));
  EXPECT_EQ(back.def.plane.lateral_tilt_deg, 2.5);
  EXPECT_EQ(back.def.bottleneck.gap_offset_mm, -1.5);
  EXPECT_EQ(back.def.particles.drag_per_s, 3.0);
  EXPECT_EQ(back.def.particles.quadratic_drag_per_m, 4.0);
  EXPECT_EQ(back.def.obstruction.corner_radius_mm, 1.0);
}

TEST(EffectKeys, OutOfRangeValuesAreRejectedWithTheKey) {
  auto error_of = [](std::vector<std::string> o) -> std::string {
    try {
      compile_text(kOneParticle, o);
    } catch (const ScenarioError& e) {
      return e.what();
    }
    return "(no error)";
  };
  EXPECT_NE(error_of({"plane.lateral_tilt_deg=10.5"}).find("'plane.lateral_tilt_deg' = 10.5: must be in [-10, 10]"),
            std::string::npos);
  EXPECT_NE(error_of({"bottleneck.gap_offset_mm=-300.0"}).find("'bottleneck.gap_offset_mm' = -300.0"), std::string::npos);
  EXPECT_NE(error_of({"bottleneck.gap_offset_mm=300.0"}).find("below plane.width_mm"), std::string::npos);
  EXPECT_NE(error_of({"particles.drag_per_s=-1.0"}).find("'particles.drag_per_s'"), std::string::npos);
  EXPECT_NE(error_of({"particles.quadratic_drag_per_m=101.0"}).find("'particles.quadratic_drag_per_m'"),
            std::string::npos);
  EXPECT_NE(error_of({"obstruction.shape=\"cylinder\"", "obstruction.distance_mm=50.0",
                      "obstruction.corner_radius_mm=1.0"})
                .find("only triangle and polygon corners"),
            std::string::npos);
  // Inradius of an equilateral triangle of side 20 mm: 20 / (2 sqrt 3) = 5.77 mm.
  std::vector<std::string> too_round = kRoundedA;
  too_round.push_back("obstruction.corner_radius_mm=5.8");
  EXPECT_NE(error_of(too_round).find("inradius, 5.774 mm"), std::string::npos) << error_of(too_round);
  too_round.back() = "obstruction.corner_radius_mm=5.7";
  EXPECT_EQ(error_of(too_round), "(no error)");
}

// ---------------------------------------------------------------- lateral tilt

// On a board rolled by phi the lone disc gains g cos(theta) sin(phi) across (+x).
TEST(LateralTilt, FrictionlessDiscSlidesAcrossAtGCosThetaSinPhi2D) {
  const CompiledScenario sc = one_particle({"plane.lateral_tilt_deg=4.0", "model.box2d.rolling.enabled=false"});
  const double expected = kStandardGravity * std::cos(sc.incline) * std::sin(deg_to_rad(4.0));
  EXPECT_NEAR(across_acceleration2d(sc) / expected, 1.0, 0.01);
}

TEST(LateralTilt, RollingDiscAcceleratesAcrossAtGCosThetaSinPhiOver1PlusK2D) {
  const CompiledScenario sc = one_particle({"plane.lateral_tilt_deg=-4.0"});
  const double expected = kStandardGravity * std::cos(sc.incline) * std::sin(deg_to_rad(-4.0)) / (1 + kK);
  EXPECT_NEAR(across_acceleration2d(sc) / expected, 1.0, 0.01);
}

TEST(LateralTilt, NormalGravityCarriesCosPhi) {
  const CompiledScenario sc = one_particle({"plane.lateral_tilt_deg=6.0"});
  EXPECT_NEAR(sc.normal_gravity(), kStandardGravity * std::cos(sc.incline) * std::cos(deg_to_rad(6.0)), 1e-12);
}

TEST(LateralTilt, RollingSphereAcceleratesAcrossAtGCosThetaSinPhiOver1PlusK3D) {
  const CompiledScenario sc = one_particle({"plane.lateral_tilt_deg=4.0"});
  Session3D s(sc);
  const double r = s.radius(0);
  s.place(0, {0, 1.0, r});
  run_for(s, 0.1);
  const double v1 = s.velocity(0).x;
  run_for(s, 0.3);
  const double a = (s.velocity(0).x - v1) / 0.3;
  const double expected = kStandardGravity * std::cos(sc.incline) * std::sin(deg_to_rad(4.0)) / (1 + kK);
  EXPECT_NEAR(a / expected, 1.0, 0.01);
}

// ---------------------------------------------------------------- gap offset

TEST(GapOffset, GeometryIsThatOfTheEffectiveGapAndTheRecordKeepsTheDeclaredW) {
  const CompiledScenario off = compile_file("scenarios/paper/cylinder.toml", {"bottleneck.gap_offset_mm=2.0"});
  const double W = off.def.bottleneck.gap_mm;
  const CompiledScenario wide =
      compile_file("scenarios/paper/cylinder.toml", {"bottleneck.gap_mm=" + std::to_string(W + 2.0)});
  EXPECT_NEAR(off.gap, wide.gap, 1e-15);
  EXPECT_NEAR(off.funnel_height, wide.funnel_height, 1e-15);
  EXPECT_NEAR(off.right_tip.x, wide.right_tip.x, 1e-15);
  EXPECT_NEAR(off.left_tip.x, wide.left_tip.x, 1e-15);
  auto same_polygon = [](const ConvexPolygon& a, const ConvexPolygon& b) {
    ASSERT_EQ(a.vertices.size(), b.vertices.size());
    for (size_t i = 0; i < a.vertices.size(); ++i) EXPECT_NEAR(length(a.vertices[i] - b.vertices[i]), 0, 1e-15);
  };
  same_polygon(off.left_bottleneck_wall, wide.left_bottleneck_wall);
  same_polygon(off.right_bottleneck_wall, wide.right_bottleneck_wall);
  ASSERT_EQ(off.particles.size(), wide.particles.size());
  for (size_t i = 0; i < off.particles.size(); ++i)
    EXPECT_NEAR(length(off.particles[i].position - wide.particles[i].position), 0, 1e-15);
  // Declared W for records and W/d.
  EXPECT_NEAR(off.declared_gap, W * 1e-3, 1e-15);
  EXPECT_NEAR(off.w_over_d(), W / off.def.particles.diameter_mm, 1e-12);
  CompiledScenario tiny = compile_text(kOneParticle, {"bottleneck.gap_offset_mm=5.0", "run.end=\"time_limit\"",
                                                      "run.time_limit_s=0.01"});
  Session2D s(tiny);
  const RunRecord rec = run_simulation(tiny, s);
  EXPECT_NEAR(rec.gap_m, 0.300, 1e-12);
  EXPECT_NEAR(tiny.gap, 0.305, 1e-12);
}

// ---------------------------------------------------------------- drag

// A sphere launched on a level board: linear drag -gamma m v on a rolling sphere
// (inertia (1+k) m) gives v2 / v1 = exp(-gamma (t2 - t1) / (1+k)); quadratic drag
// -c m |v| v gives v2 = v1 / (1 + c v1 (t2 - t1) / (1+k)). Measured from t1 = 0.1 s,
// after the 3D sphere has turned its initial slide into rolling.
struct Decay {
  double v1, v2;
};
const double kV0 = 0.5, kT1 = 0.1, kSpan = 0.5;  // m/s, s, s

Decay decay2d(const CompiledScenario& sc) {
  Session2D s(sc);
  launch2d(s, {0, 1.0}, {0, kV0});
  run_for(s, kT1);
  const double v1 = velocity2d(s).y;
  run_for(s, kSpan);
  return {v1, velocity2d(s).y};
}

Decay decay3d(const CompiledScenario& sc) {
  Session3D s(sc);
  s.place(0, {0, 1.0, s.radius(0)}, {0, kV0, 0});
  run_for(s, kT1);
  const double v1 = s.velocity(0).y;
  run_for(s, kSpan);
  return {v1, s.velocity(0).y};
}

const std::vector<std::string> kLinearDrag = {"plane.incline_deg=0.0", "particles.drag_per_s=2.0"};
const std::vector<std::string> kQuadraticDrag = {"plane.incline_deg=0.0", "particles.quadratic_drag_per_m=3.0"};

TEST(Drag, LinearDragDecaysARollingSphereAtGammaOver1PlusK2D) {
  const Decay d = decay2d(one_particle(kLinearDrag));
  EXPECT_NEAR(d.v1 / kV0, std::exp(-2.0 * kT1 / (1 + kK)), 0.01);
  EXPECT_NEAR(d.v2 / d.v1, std::exp(-2.0 * kSpan / (1 + kK)), 0.01 * std::exp(-2.0 * kSpan / (1 + kK)));
}

TEST(Drag, LinearDragDecaysARollingSphereAtGammaOver1PlusK3D) {
  const Decay d = decay3d(one_particle(kLinearDrag));
  const double expected = std::exp(-2.0 * kSpan / (1 + kK));
  EXPECT_NEAR(d.v2 / d.v1, expected, 0.01 * expected);
}

TEST(Drag, QuadraticDragFollowsV1Over1PlusCV1TOver1PlusK2D) {
  const Decay d = decay2d(one_particle(kQuadraticDrag));
  const double expected = d.v1 / (1 + 3.0 * d.v1 * kSpan / (1 + kK));
  EXPECT_NEAR(d.v2 / expected, 1.0, 0.01);
  EXPECT_LT(d.v2, 0.8 * d.v1);  // the drag is strong enough to matter
}

TEST(Drag, QuadraticDragFollowsV1Over1PlusCV1TOver1PlusK3D) {
  const Decay d = decay3d(one_particle(kQuadraticDrag));
  const double expected = d.v1 / (1 + 3.0 * d.v1 * kSpan / (1 + kK));
  EXPECT_NEAR(d.v2 / expected, 1.0, 0.01);
  EXPECT_LT(d.v2, 0.8 * d.v1);
}

// ---------------------------------------------------------------- rounded corners

// Equilateral triangle of side s = 20 mm, corners rounded with r = 2 mm; D = 50 mm (nearest).
// A (flat face toward the gap): the face stays at D. V (apex toward the gap): the core's apex
// lies 2r up the bisector (half-angle 30 degrees), the rounded apex at D + 2r - r = D + r.
TEST(CornerRadius, RoundedVAndAAgainstHandComputedOutlines) {
  const double s = 20e-3, r = 2e-3, D = 50e-3;
  const CompiledScenario a = compile_text(kOneParticle, {"obstruction.shape=\"A\"", "obstruction.distance_mm=50.0",
                                                         "obstruction.corner_radius_mm=2.0"});
  const CompiledScenario v = compile_text(kOneParticle, {"obstruction.shape=\"V\"", "obstruction.distance_mm=50.0",
                                                         "obstruction.corner_radius_mm=2.0"});
  EXPECT_NEAR(a.obstruction.nearest_y, D, 1e-12);
  EXPECT_NEAR(v.obstruction.nearest_y, D + r, 1e-12);
  EXPECT_NEAR(a.obstruction.corner_radius, r, 1e-15);
  // The core is the equilateral triangle of side s - 2 sqrt(3) r about the same incentre.
  for (const CompiledScenario* c : {&a, &v}) {
    const std::vector<Vec2>& core = c->obstruction.polygon.vertices;
    ASSERT_EQ(core.size(), 3u);
    for (size_t i = 0; i < 3; ++i) EXPECT_NEAR(length(core[i] - core[(i + 1) % 3]), s - 2 * std::sqrt(3.0) * r, 1e-12);
  }
  // V: the core's apex, and the distance from a point 1 mm below the drawn apex.
  Vec2 apex{0, 1};
  for (Vec2 p : v.obstruction.polygon.vertices)
    if (p.y < apex.y) apex = p;
  EXPECT_NEAR(apex.x, 0, 1e-12);
  EXPECT_NEAR(apex.y, D + 2 * r, 1e-12);
  EXPECT_NEAR(obstruction_distance(v.obstruction, {0, D - 1e-3}), r + 1e-3, 1e-12);
  // A: its bottom face is still at D; the bottom corners are cut.
  EXPECT_NEAR(obstruction_distance(a.obstruction, {0, D - 1e-3}), 1e-3, 1e-12);
  EXPECT_GT(obstruction_distance(a.obstruction, {-s / 2, D}), 0.5 * r);
  // The clog-front occlusion test sees the rounded apex: a chord 0.5 mm above the drawn apex
  // passes below the rounded V; one at D + r + 0.5 mm passes through it.
  EXPECT_FALSE(obstruction_blocks_segment(v.obstruction, {-1e-3, D + 0.5e-3}, {1e-3, D + 0.5e-3}));
  EXPECT_TRUE(obstruction_blocks_segment(v.obstruction, {-1e-3, D + r + 0.5e-3}, {1e-3, D + r + 0.5e-3}));
  const CompiledScenario sharp = compile_text(kOneParticle, {"obstruction.shape=\"V\"", "obstruction.distance_mm=50.0"});
  EXPECT_TRUE(obstruction_blocks_segment(sharp.obstruction, {-1e-3, D + 0.5e-3}, {1e-3, D + 0.5e-3}));
}

TEST(CornerRadius, InwardOffsetDropsVanishingEdgesAndInradiusIsTheLargestDisc) {
  // A 10 x 2 rectangle: inradius 1; offset by 0.5 leaves a 9 x 1 rectangle.
  const ConvexPolygon rect{{{0, 0}, {10, 0}, {10, 2}, {0, 2}}};
  EXPECT_NEAR(inradius(rect), 1.0, 1e-9);
  const ConvexPolygon in = inward_offset(rect, 0.5);
  ASSERT_EQ(in.vertices.size(), 4u);
  EXPECT_NEAR(std::abs(signed_area2(in.vertices)) / 2, 9.0, 1e-12);
  // A triangle with a very short edge: that edge vanishes before the inradius is reached.
  const ConvexPolygon tri{{{0, 0}, {10, 0}, {10.05, 0.1}, {0, 5}}};
  const double rho = inradius(tri);
  EXPECT_FALSE(inward_offset(tri, 0.9 * rho).vertices.empty());
  EXPECT_TRUE(inward_offset(tri, 1.01 * rho).vertices.empty());
}

// A, corners rounded with r = 2 mm, 200 mm up the board; the core's apex (uphill corner).
const std::vector<std::string> kRoundedAUphill = {"obstruction.shape=\"A\"", "obstruction.distance_mm=200.0",
                                                  "obstruction.corner_radius_mm=2.0"};
Vec2 core_apex(const CompiledScenario& sc) {
  Vec2 apex{0, 0};
  for (Vec2 p : sc.obstruction.polygon.vertices)
    if (p.y > apex.y) apex = p;
  return apex;
}

// A disc resting on the rounded apex of an A (pointing uphill, away from the gap) sits at
// distance r + R from the core's apex (Box2D's polygon skin m_radius = r).
TEST(CornerRadius, DiscRestsOnARoundedCornerAtRPlusItsRadius2D) {
  const double r = 2e-3;
  const CompiledScenario sc = one_particle(kRoundedAUphill);
  const Vec2 apex = core_apex(sc);
  const double R = sc.particles[0].diameter / 2;
  Session2D s(sc);
  launch2d(s, {apex.x, apex.y + r + R + 0.2e-3}, {0, 0});
  run_for(s, 0.2);
  std::vector<ActiveParticle> active;
  s.active_particles(active);
  EXPECT_NEAR(length(active[0].position - apex), r + R, 0.01 * sc.nominal_diameter);
  EXPECT_NEAR(active[0].position.x, apex.x, 0.01 * sc.nominal_diameter);  // still on the apex
}

// The same in 3D: Bullet's hull of the core with margin r.
TEST(CornerRadius, SphereRestsOnARoundedCornerAtRPlusItsRadius3D) {
  const double r = 2e-3;
  const CompiledScenario sc = one_particle(kRoundedAUphill);
  const Vec2 apex = core_apex(sc);
  Session3D s(sc);
  const double R = s.radius(0);
  s.place(0, {apex.x, apex.y + r + R + 0.2e-3, R});
  run_for(s, 0.2);
  const Vec3Lab p = s.position(0);
  EXPECT_NEAR(std::hypot(p.x - apex.x, p.y - apex.y), r + R, 0.01 * sc.nominal_diameter);
}

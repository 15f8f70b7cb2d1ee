// The rolling-contact effect (model.box2d.rolling_contact, sim2d/effects2d.hpp): the force law
// alone, then in the running model against cases with a known answer: a column of spheres
// behind a stop (force balance), a pushed column (energy bookkeeping), a head-on pair (no
// sliding, no loss), and a whole discharge (nothing escapes, J drops).
#include "common/scenario_loader.hpp"
#include "common/simulation.hpp"
#include "common/units.hpp"
#include "common/vec2_math.hpp"
#include "sim2d/effects2d.hpp"
#include "sim2d/session2d.hpp"
#include "tests/test_support.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

using namespace gapflow;
using gapflow::testing::compile_file;
using gapflow::testing::compile_text;

// ---------------------------------------------------------------- the force law

namespace {
const double kMu = 0.24, kFn = 2.0;  // -, N
}

TEST(RollingContactLaw, PushingPairIsBrakedAlongTheNormalWithMuFn) {
  // i behind j, both rolling along n at 0.3 m/s: the contact slides at 2 v.
  const Vec2 n{0, 1}, v{0, 0.3};
  const Vec2 f = rolling_contact_force(v, v, n, kFn, kMu, 0, 0);
  EXPECT_DOUBLE_EQ(f.x, 0);
  EXPECT_DOUBLE_EQ(f.y, -kMu * kFn);  // against the motion, on both spheres
  // Moving the other way along n: the force turns with the motion.
  EXPECT_DOUBLE_EQ(rolling_contact_force(-1.0 * v, -1.0 * v, n, kFn, kMu, 0, 0).y, kMu * kFn);
  // A sphere rolling into a wall (v_j = 0: the wall does not roll) is braked too.
  EXPECT_DOUBLE_EQ(rolling_contact_force(v, {0, 0}, n, kFn, 0.5, 0, 0).y, -0.5 * kFn);
}

TEST(RollingContactLaw, HeadOnAndSideBySideDoNotSlide) {
  const Vec2 n{0.6, 0.8};
  const Vec2 f_head_on = rolling_contact_force(0.3 * n, -0.3 * n, n, kFn, kMu, 0, 0);
  EXPECT_EQ(f_head_on.x, 0);
  EXPECT_EQ(f_head_on.y, 0);
  const Vec2 along{-0.8 * 0.3, 0.6 * 0.3};  // perpendicular to n
  const Vec2 f_side = rolling_contact_force(along, along, n, kFn, kMu, 0, 0);
  EXPECT_NEAR(f_side.x, 0, 1e-15);
  EXPECT_NEAR(f_side.y, 0, 1e-15);
  // Rolling along a wall: no sliding either.
  EXPECT_NEAR(length(rolling_contact_force(along, {0, 0}, n, kFn, kMu, 0, 0)), 0, 1e-15);
}

TEST(RollingContactLaw, PowerIsMinusMuFnTimesTheSlidingSpeed) {
  // Seeded pseudo-random cases: f.v_i + f.v_j = -mu F_n |n.(v_i + v_j)|.
  std::uint64_t state = 12345;
  auto uniform = [&]() {  // LCG in [-1, 1)
    state = state * 6364136223846793005ull + 1442695040888963407ull;
    return static_cast<double>(state >> 11) / 4503599627370496.0 - 1.0;
  };
  for (int c = 0; c < 200; ++c) {
    const Vec2 vi{uniform(), uniform()}, vj{uniform(), uniform()};
    const double a = 3.14159 * uniform();
    const Vec2 n{std::cos(a), std::sin(a)};
    const double fn = 1 + uniform(), mu = 0.5 + 0.4 * uniform();
    const Vec2 f = rolling_contact_force(vi, vj, n, fn, mu, 0, 0);
    EXPECT_NEAR(dot(f, vi) + dot(f, vj), -mu * fn * std::abs(dot(n, vi + vj)), 1e-12) << c;
    EXPECT_NEAR(length(f), mu * fn, 1e-12) << c;
  }
}

TEST(RollingContactLaw, ClampStopsTheSlidingButNeverReversesIt) {
  const Vec2 n{0, 1};
  const double h = 1e-3, mi = 0.002, mj = 0.003;  // s, kg (unequal bodies)
  for (double fn : {0.01, 10.0, 100.0}) {         // N: unclamped, clamped, far beyond
    const Vec2 vi{0.1, 0.2}, vj{-0.3, 0.05};
    const Vec2 f = rolling_contact_force(vi, vj, n, fn, kMu, 1 / mi + 1 / mj, h);
    const Vec2 vi2 = vi + (h / mi) * f, vj2 = vj + (h / mj) * f;
    const double s0 = dot(n, vi + vj), s1 = dot(n, vi2 + vj2);
    EXPECT_GE(s1, -1e-15) << fn;  // stopped at most
    EXPECT_LT(s1, s0) << fn;      // but braked
    if (fn >= 10.0) {
      EXPECT_NEAR(s1, 0, 1e-15) << "large forces stop the sliding exactly";
    } else {
      EXPECT_DOUBLE_EQ(length(f), kMu * fn);
    }
  }
  // Against a wall (one body).
  const Vec2 v{0, -0.01};
  const Vec2 f = rolling_contact_force(v, {0, 0}, n, 100.0, kMu, 1 / mi, h);
  EXPECT_NEAR(dot(n, v + (h / mi) * f), 0, 1e-15);
}

// ---------------------------------------------------------------- in the running model

namespace {

// A few spheres, no settling; they are placed by hand (x = 0, a column down the fall line).
std::string column_scenario(int count, double incline_deg) {
  return gapflow::testing::open_board_scenario("rolling contact column", count, incline_deg);
}

// Mean contact forces (engine N) of a column of spheres 0, 1, ... upward along +y on x = 0,
// sphere 0 resting on a kinematic stop that moves at (0, v) (lab m/s), as are the spheres at
// the start; averaged over [0.4, 0.8] s. `effect_power`: the mean of sum lambda mu F_n |s| over
// the contacts (engine W), with each contact's measured F_n, friction and velocities.
struct ColumnForces {
  double wall = 0;            // stop on sphere 0
  std::vector<double> pair;   // sphere k on k+1
  double effect_power = 0;    // engine W
  double weight = 0;          // m g sin(theta) of one sphere (engine N)
  double board_normal = 0;    // m g cos(theta) of one sphere (engine N)
  double v_engine = 0;        // stop speed (engine m/s)
};

ColumnForces column_forces(const CompiledScenario& sc, double v_lab) {
  Session2D s(sc);
  s.set_barrier(false);
  World2D& w = s.world();
  const int n = static_cast<int>(w.particles.size());
  const float r = static_cast<float>(w.props[0].radius);
  const b2Vec2 base = w.to_engine({0, 1.0});
  const float v = static_cast<float>(w.scale.to_engine_velocity(v_lab));

  b2BodyDef bd;
  bd.type = b2_kinematicBody;
  bd.position = {base.x, base.y - 2 * r};  // its top face touches sphere 0
  b2Body* stop = w.world->CreateBody(&bd);
  b2PolygonShape box;
  box.SetAsBox(3 * r, r);
  b2FixtureDef fd;
  fd.shape = &box;
  fd.userData.pointer = static_cast<uintptr_t>(FixtureKind::wall);
  stop->CreateFixture(&fd);
  stop->SetLinearVelocity({0, v});
  for (int k = 0; k < n; ++k) {
    w.particles[static_cast<size_t>(k)]->SetTransform({base.x, base.y + 2 * r * static_cast<float>(k)}, 0);
    w.particles[static_cast<size_t>(k)]->SetLinearVelocity({0, v});
  }

  ColumnForces out;
  out.pair.assign(static_cast<size_t>(n - 1), 0.0);
  const double lambda = sc.def.model.box2d.rolling_contact, h = w.dt_engine;
  const double g = w.scale.to_engine_acceleration(kStandardGravity);
  out.weight = w.props[0].true_mass * g * std::sin(sc.incline);
  out.board_normal = w.props[0].true_mass * w.normal_gravity;
  out.v_engine = v;
  const long settle = std::lround(0.4 / s.time_step()), measure = std::lround(0.4 / s.time_step());
  for (long step = 0; step < settle + measure; ++step) {
    s.step();
    if (step < settle) continue;
    for (b2Contact* c = w.world->GetContactList(); c; c = c->GetNext()) {
      if (!c->IsTouching()) continue;
      double fn = 0;
      for (int p = 0; p < c->GetManifold()->pointCount; ++p) fn += c->GetManifold()->points[p].normalImpulse / h;
      b2Body* a = c->GetFixtureA()->GetBody();
      b2Body* b = c->GetFixtureB()->GetBody();
      const int ia = static_cast<int>(a->GetUserData().pointer) - 1, ib = static_cast<int>(b->GetUserData().pointer) - 1;
      b2WorldManifold wm;
      c->GetWorldManifold(&wm);
      const Vec2 normal{wm.normal.x, wm.normal.y};  // A to B
      Vec2 slip{0, 0};                              // v_i + v_j (v_j = 0 for the stop)
      if (a == stop || b == stop) {
        out.wall += fn / static_cast<double>(measure);
        b2Body* sphere = a == stop ? b : a;
        slip = {sphere->GetLinearVelocity().x, sphere->GetLinearVelocity().y};
      } else if (ia >= 0 && ib >= 0) {
        out.pair.at(static_cast<size_t>(std::min(ia, ib))) += fn / static_cast<double>(measure);
        slip = {a->GetLinearVelocity().x + b->GetLinearVelocity().x, a->GetLinearVelocity().y + b->GetLinearVelocity().y};
      }
      out.effect_power += lambda * c->GetFriction() * fn * std::abs(dot(normal, slip)) / static_cast<double>(measure);
    }
  }
  return out;
}

}  // namespace

// ---------------------------------------------------------------- the key

TEST(RollingContactKey, DefaultIsOffAndUnwrittenSetValueReadsBackOutOfRangeIsRejected) {
  const std::string text = column_scenario(3, 8.0);
  const LoadedScenario plain = parse_scenario(text, "k.toml");
  EXPECT_EQ(plain.def.model.box2d.rolling_contact, 0.0);
  EXPECT_EQ(canonical_toml(plain.def).find("rolling_contact"), std::string::npos) << "hashes stay valid";
  const LoadedScenario on = parse_scenario(text, "k.toml", {"model.box2d.rolling_contact=0.75"});
  const LoadedScenario back = parse_scenario(canonical_toml(on.def), "back.toml");
  EXPECT_EQ(back.def.model.box2d.rolling_contact, 0.75);
  EXPECT_NE(scenario_hash(on.def), scenario_hash(plain.def));
  auto error_of = [&](const std::vector<std::string>& o, const std::string& t = "") -> std::string {
    try {
      parse_scenario(t.empty() ? text : t, "k.toml", o);
    } catch (const ScenarioError& e) {
      return e.what();
    }
    return "(no error)";
  };
  EXPECT_NE(error_of({"model.box2d.rolling_contact=1.5"})
                .find("'model.box2d.rolling_contact' = 1.5: must be in [0, 1] (fraction of the derived force)"),
            std::string::npos)
      << error_of({"model.box2d.rolling_contact=1.5"});
  EXPECT_NE(error_of({"model.box2d.rolling_contact=-0.1"}).find("--set:1:"), std::string::npos);
  EXPECT_NE(error_of({"model.box2d.rolling_contact=0.5", "model.box2d.rolling.enabled=false"})
                .find("must be 0 when model.box2d.rolling.enabled = false"),
            std::string::npos);
  // In a file: file:line:column.
  const std::string file_error = error_of({}, text + "[model.box2d]\nrolling_contact = 2.0\n");
  EXPECT_NE(file_error.find("k.toml:17:"), std::string::npos) << file_error;
}

// Spheres rolling down the 8-degree board at 0.1 m/s behind a stop that descends at that speed.
// Sphere k (from the top, K spheres above the stop): G + F_above (1 - lambda mu) = F_below (1 + lambda mu'),
// G = m g sin(theta), mu' the coefficient below it (mu_w for the stop): the top pair carries
// G/(1 + lambda mu), the stop 3 G without the effect.
TEST(RollingContactModel, ColumnBehindADescendingStopCarriesTheForcesOfTheLaw) {
  const double mu = 0.24, mu_w = 0.5;
  for (double lambda : {0.0, 0.5, 1.0}) {
    const CompiledScenario sc = compile_text(
        column_scenario(3, 8.0), {"particles.friction_wall=0.5", "model.box2d.rolling_contact=" + std::to_string(lambda)});
    const ColumnForces f = column_forces(sc, -0.1);
    const double G = f.weight, lm = lambda * mu;
    const double top = G / (1 + lm), middle = (G + (1 - lm) * top) / (1 + lm);
    const double wall = (G + (1 - lm) * middle) / (1 + lambda * mu_w);
    EXPECT_NEAR(f.pair[1] / top, 1.0, 0.01) << "lambda " << lambda;
    EXPECT_NEAR(f.pair[0] / middle, 1.0, 0.01) << "lambda " << lambda;
    EXPECT_NEAR(f.wall / wall, 1.0, 0.01) << "lambda " << lambda;
    if (lambda == 1.0) {
      EXPECT_LT(f.wall, 0.6 * 3 * G) << "the effect is large: a test that can fail";
    }
  }
}

// At rest nothing slides: the stop carries the whole weight of the column with the effect on.
TEST(RollingContactModel, ColumnAtRestOnAStaticStopFeelsNoFriction) {
  const CompiledScenario sc = compile_text(column_scenario(3, 8.0), {"model.box2d.rolling_contact=1.0"});
  const ColumnForces f = column_forces(sc, 0.0);
  EXPECT_NEAR(f.wall / (3 * f.weight), 1.0, 0.01);
  EXPECT_NEAR(f.pair[0] / (2 * f.weight), 1.0, 0.01);
  EXPECT_NEAR(f.pair[1] / f.weight, 1.0, 0.01);
}

// With mu = 2 every sphere's braking exceeds what the board can supply: each is braked by exactly
// the cap (1+k) mu_base m g cos(theta), so the stop carries 3 (G - cap).
TEST(RollingContactModel, BrakingIsCappedByTheBoardFriction) {
  const CompiledScenario sc =
      compile_text(column_scenario(3, 8.0), {"particles.friction_particle=2.0", "particles.friction_wall=2.0",
                                             "particles.friction_base=0.06", "model.box2d.rolling_contact=1.0"});
  const ColumnForces f = column_forces(sc, -0.1);
  const double cap = 1.4 * 0.06 * f.board_normal;
  ASSERT_GT(2.0 * f.weight / 3.0, cap) << "the top sphere's braking must reach the cap too";
  EXPECT_NEAR(f.wall / (3 * (f.weight - cap)), 1.0, 0.01);
  EXPECT_NEAR(f.pair[1] / (f.weight - cap), 1.0, 0.01);
}

// A column of three pushed along a level board at 0.1 m/s against rolling resistance mu_r: in
// steady state the pusher's power F_w V goes into rolling resistance 3 mu_r m g V and into the
// contacts' sliding friction sum lambda mu F_n |n.(v_i + v_j)| (measured F_n and velocities).
// Without the effect the pusher's work is the rolling resistance's alone.
TEST(RollingContactModel, PushedColumnEnergyBookkeeping) {
  for (double lambda : {0.0, 1.0}) {
    const CompiledScenario sc = compile_text(column_scenario(3, 0.0), {"particles.rolling_resistance=0.02",
                                                                       "model.box2d.rolling_contact=" + std::to_string(lambda)});
    const ColumnForces f = column_forces(sc, 0.1);
    const double p_in = f.wall * f.v_engine, p_rr = 3 * 0.02 * f.board_normal * f.v_engine;
    EXPECT_NEAR((p_in - p_rr - f.effect_power) / p_in, 0.0, 0.01) << "lambda " << lambda;
    if (lambda == 0) {
      EXPECT_NEAR(f.wall / (3 * 0.02 * f.board_normal), 1.0, 0.01);
    }
    // mu = mu_w = 0.24: F_w = 6.97 mu_r m g (front pair R/(1 - mu), next (R + (1 + mu) F)/(1 - mu), ...).
    if (lambda == 1) {
      const double R = 0.02 * f.board_normal, mu = 0.24;
      const double f12 = R / (1 - mu), f01 = (R + (1 + mu) * f12) / (1 - mu), fw = (R + (1 + mu) * f01) / (1 - mu);
      EXPECT_NEAR(f.wall / fw, 1.0, 0.01);
      EXPECT_GT(f.effect_power, 0.5 * p_in) << "most of the pusher's work is sliding friction";
    }
  }
}

// Two spheres rolling head-on into each other on a level board: the contact does not slide, so the
// run is bit-identical with the effect on and off; a sphere rolling into a resting one (pushing)
// loses momentum with the effect on.
TEST(RollingContactModel, HeadOnPairLosesNothingExtraAPushingImpactDoes) {
  auto final_velocities = [](double lambda, double vj) {
    const CompiledScenario sc =
        compile_text(column_scenario(2, 0.0), {"model.box2d.rolling_contact=" + std::to_string(lambda)});
    Session2D s(sc);
    s.set_barrier(false);
    World2D& w = s.world();
    const float r = static_cast<float>(w.props[0].radius), v = static_cast<float>(w.scale.to_engine_velocity(0.3));
    const b2Vec2 c = w.to_engine({0, 1.0});
    w.particles[0]->SetTransform({c.x - 3 * r, c.y}, 0);
    w.particles[1]->SetTransform({c.x + 3 * r, c.y}, 0);
    w.particles[0]->SetLinearVelocity({v, 0});
    w.particles[1]->SetLinearVelocity({static_cast<float>(vj) * v, 0});
    for (int i = 0; i < 300; ++i) s.step();
    return std::vector<float>{w.particles[0]->GetLinearVelocity().x, w.particles[1]->GetLinearVelocity().x,
                              w.particles[0]->GetLinearVelocity().y, w.particles[1]->GetLinearVelocity().y};
  };
  EXPECT_EQ(final_velocities(1.0, -1.0), final_velocities(0.0, -1.0)) << "head-on: identical";
  const std::vector<float> on = final_velocities(1.0, 0.0), off = final_velocities(0.0, 0.0);
  EXPECT_LT(on[0] + on[1], 0.999f * (off[0] + off[1])) << "pushing impact: braked";
  EXPECT_GT(on[0] + on[1], 0.0f);
}

// The paper's medium discharge, small (300 spheres, W = 40 mm): with the effect at its derived
// size every particle passes, none escapes, and the flow is slower than without it.
TEST(RollingContactModel, SmallMediumDischargePassesEveryParticleAndSlowsDown) {
  auto run = [](double lambda) {
    const CompiledScenario sc =
        compile_file("scenarios/paper/no_obstruction_medium.toml",
                     {"particles.count=300", "bottleneck.gap_mm=40", "model.box2d.rolling_contact=" + std::to_string(lambda)});
    Session2D s(sc);
    return run_simulation(sc, s);
  };
  const RunRecord on = run(1.0), off = run(0.0);
  EXPECT_EQ(on.passed, 300);
  EXPECT_EQ(on.escaped, 0);
  EXPECT_EQ(on.max_conservation_error, 0);
  ASSERT_TRUE(on.j_paper && off.j_paper);
  EXPECT_LT(*on.j_paper, 0.95 * *off.j_paper) << *on.j_paper << " vs " << *off.j_paper << " /s";
}

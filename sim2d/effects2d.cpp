#include "sim2d/effects2d.hpp"

#include "common/vec2_math.hpp"

#include <algorithm>
#include <cmath>

namespace gapflow {

void RollingEffect::shape_bodies(BodyModel2D& model) const {
  model.translational_mass_factor *= 1.0 + k_;
  model.gravity_factor /= 1.0 + k_;
  model.spin_inertia_factor = k_;  // a sphere is isotropic: same factor about the board normal
}

BaseFrictionEffect::BaseFrictionEffect(BaseFrictionMethod method, double rolling_resistance,
                                       double spinning_friction_m)
    : method_(method), mu_r_(rolling_resistance), spin_len_m_(spinning_friction_m) {}

namespace {

// Largest resisting force and torque from the board on particle i (engine units).
struct BoardLimits {
  float force;
  float torque;
};
BoardLimits board_limits(const World2D& w, int i, double mu_r, double spin_len_m) {
  const double normal = w.props[static_cast<size_t>(i)].true_mass * w.normal_gravity;  // m g cos(theta)
  return {static_cast<float>(mu_r * normal),
          static_cast<float>(w.scale.to_engine_length(spin_len_m) * normal)};
}

}  // namespace

void BaseFrictionEffect::attach(World2D& w) {
  if (method_ != BaseFrictionMethod::joint) return;
  // One friction joint per particle to the static ground: the solver applies at
  // most maxForce/maxTorque, implicitly, so the particle stops exactly.
  for (int i : w.active) {
    b2FrictionJointDef def;
    def.Initialize(w.ground, w.particles[static_cast<size_t>(i)], w.particles[static_cast<size_t>(i)]->GetPosition());
    const BoardLimits lim = board_limits(w, i, mu_r_, spin_len_m_);
    def.maxForce = lim.force;
    def.maxTorque = lim.torque;
    def.collideConnected = true;
    w.world->CreateJoint(&def);
  }
}

void BaseFrictionEffect::before_step(World2D& w) {
  if (method_ != BaseFrictionMethod::force) return;
  const auto inv_dt = static_cast<float>(1.0 / w.dt_engine);
  for (int i : w.active) {
    b2Body* b = w.particles[static_cast<size_t>(i)];
    const BoardLimits lim = board_limits(w, i, mu_r_, spin_len_m_);
    const b2Vec2 v = b->GetLinearVelocity();
    const float speed = v.Length();
    if (speed > 0 && lim.force > 0) {
      // Never more than what stops the particle within this step.
      const float f = std::min(lim.force, b->GetMass() * speed * inv_dt);
      b->ApplyForceToCenter((-f / speed) * v, false);
    }
    const float w_spin = b->GetAngularVelocity();
    if (w_spin != 0 && lim.torque > 0) {
      const float tq = std::min(lim.torque, b->GetInertia() * std::abs(w_spin) * inv_dt);
      b->ApplyTorque(w_spin > 0 ? -tq : tq, false);
    }
  }
}

void LinearDragEffect::attach(World2D& w) {
  const double h = w.dt_engine;
  for (int i : w.active) {
    b2Body* b = w.particles[static_cast<size_t>(i)];
    // Decay rate of the body: the drag acts on the sphere's mass, the body has the rolling mass.
    const double rate = w.scale.to_engine_rate(gamma_) * w.props[static_cast<size_t>(i)].true_mass / b->GetMass();
    b->SetLinearDamping(static_cast<float>(std::expm1(h * rate) / h));
  }
}

void QuadraticDragEffect::before_step(World2D& w) {
  const double c = c_ / w.scale.length;  // 1/(engine length)
  const double h = w.dt_engine;
  for (int i : w.active) {
    b2Body* b = w.particles[static_cast<size_t>(i)];
    const b2Vec2 v = b->GetLinearVelocity();
    const double speed = v.Length();
    if (speed <= 0) continue;
    const double m = w.props[static_cast<size_t>(i)].true_mass, M = b->GetMass();
    // Force that turns v into v / (1 + c (m/M) |v| h) over the step.
    const double f = c * m * speed * speed / (1 + c * (m / M) * speed * h);
    b->ApplyForceToCenter(static_cast<float>(-f / speed) * v, false);
  }
}

Vec2 rolling_contact_force(Vec2 vi, Vec2 vj, Vec2 n, double normal_force, double mu, double inv_mass_sum,
                           double h) {
  const double s = dot(n, vi + vj);  // vertical sliding speed at the contact
  if (s == 0 || normal_force <= 0 || mu <= 0) return {0, 0};
  double f = mu * normal_force;
  // Over h both spheres gain -f sign(s) n h / M: s changes by -f sign(s) h inv_mass_sum.
  if (h > 0 && inv_mass_sum > 0) f = std::min(f, std::abs(s) / (h * inv_mass_sum));
  return (s > 0 ? -f : f) * n;
}

namespace {

Vec2 vec(b2Vec2 v) { return {v.x, v.y}; }

// Particle id of a fixture's body, -1 for walls, obstruction and barrier.
int particle_id(b2Fixture* f) {
  if (static_cast<FixtureKind>(f->GetUserData().pointer) != FixtureKind::particle) return -1;
  return static_cast<int>(f->GetBody()->GetUserData().pointer) - 1;
}

}  // namespace

void RollingContactEffect::before_step(World2D& w) {
  const double h = w.dt_engine;
  force_.assign(w.particles.size(), b2Vec2_zero);
  for (b2Contact* c = w.world->GetContactList(); c; c = c->GetNext()) {
    if (!c->IsTouching() || !c->IsEnabled()) continue;
    const b2Manifold* m = c->GetManifold();
    double impulse = 0;  // solved in the previous step
    for (int k = 0; k < m->pointCount; ++k) impulse += m->points[k].normalImpulse;
    if (impulse <= 0) continue;
    int i = particle_id(c->GetFixtureA()), j = particle_id(c->GetFixtureB());
    if (i < 0 && j < 0) continue;
    b2WorldManifold wm;
    c->GetWorldManifold(&wm);  // normal from A to B
    Vec2 n = vec(wm.normal);
    if (i < 0) {  // the particle is B: its partner (a wall) is A
      std::swap(i, j);
      n = -1.0 * n;
    }
    b2Body* bi = w.particles[static_cast<size_t>(i)];
    b2Body* bj = j >= 0 ? w.particles[static_cast<size_t>(j)] : nullptr;
    const Vec2 vj = bj ? vec(bj->GetLinearVelocity()) : Vec2{0, 0};  // a wall does not roll
    const double inv_mass = 1.0 / bi->GetMass() + (bj ? 1.0 / bj->GetMass() : 0.0);
    const Vec2 f = rolling_contact_force(vec(bi->GetLinearVelocity()), vj, n, impulse / h,
                                         lambda_ * c->GetFriction(), inv_mass, h);
    const b2Vec2 fe(static_cast<float>(f.x), static_cast<float>(f.y));
    force_[static_cast<size_t>(i)] += fe;
    if (bj) force_[static_cast<size_t>(j)] += fe;
  }
  for (int i : w.active) {
    b2Vec2 f = force_[static_cast<size_t>(i)];
    const double len = f.Length();
    if (len == 0) continue;
    // The board's friction supplies f/(1+k): at most mu_base m g cos(theta).
    const double cap = (1 + k_) * mu_base_ * w.props[static_cast<size_t>(i)].true_mass * w.normal_gravity;
    if (len > cap) f *= static_cast<float>(cap / len);
    w.particles[static_cast<size_t>(i)]->ApplyForceToCenter(f, false);
  }
}

std::vector<std::unique_ptr<ReducedEffect2D>> make_effects2d(const CompiledScenario& sc) {
  std::vector<std::unique_ptr<ReducedEffect2D>> effects;
  const Box2DDef& m = sc.def.model.box2d;
  if (m.rolling.enabled) effects.push_back(std::make_unique<RollingEffect>(m.rolling.inertia_factor));
  const ParticlesDef& p = sc.def.particles;
  if (m.base_friction.enabled && (p.rolling_resistance > 0 || p.spinning_friction_mm > 0))
    effects.push_back(std::make_unique<BaseFrictionEffect>(m.base_friction.method, p.rolling_resistance,
                                                           p.spinning_friction_mm * 1e-3));
  if (p.drag_per_s > 0) effects.push_back(std::make_unique<LinearDragEffect>(p.drag_per_s));
  if (p.quadratic_drag_per_m > 0) effects.push_back(std::make_unique<QuadraticDragEffect>(p.quadratic_drag_per_m));
  if (m.rolling_contact > 0) effects.push_back(std::make_unique<RollingContactEffect>(m.rolling_contact, p.friction_base,
                                                                m.rolling.inertia_factor));
  return effects;
}

}  // namespace gapflow

#include "sim2d/effects2d.hpp"

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
  return effects;
}

}  // namespace gapflow

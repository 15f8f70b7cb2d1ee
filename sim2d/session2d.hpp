// Session2D: one run of the Box2D model (per-run state, like MuJoCo's mjData).
// Exposed for white-box tests (velocities, kinematic bodies); everything else
// goes through EngineSession.
#pragma once

#include "sim2d/effects2d.hpp"
#include "sim2d/model2d.hpp"
#include "sim2d/world2d.hpp"

#include <stdexcept>

namespace gapflow {

class Session2D final : public EngineSession {
 public:
  explicit Session2D(const CompiledScenario& sc) : sc_(sc), effects_(make_effects2d(sc)) {
    BodyModel2D model;
    model.spin_inertia_factor = sc.def.model.box2d.spin_inertia_factor;  // the rolling effect overrides it
    for (const auto& e : effects_) e->shape_bodies(model);
    w_ = build_world2d(sc, model);
    for (const auto& e : effects_) e->attach(*w_);
  }

  std::string model_name() const override { return "2d"; }
  double time_step() const override { return sc_.def.model.box2d.time_step_s; }
  void set_barrier(bool closed) override { set_barrier2d(*w_, sc_, closed); }

  void set_shake_targets(const ShakeOffsets& o) override {
    follow(w_->left_wall, w_->left_wall_rest, o.left_wall);
    follow(w_->right_wall, w_->right_wall_rest, o.right_wall);
    follow(w_->obstruction, w_->obstruction_rest, o.obstruction);
  }

  void step() override {
    for (const auto& e : effects_) e->before_step(*w_);  // stage: reduced-model forces
    w_->world->Step(static_cast<float>(w_->dt_engine), w_->velocity_iterations,
                    w_->position_iterations);             // stage: contacts and integration
  }

  void zero_velocities() override {
    for (int i : w_->active) {
      b2Body* b = w_->particles[static_cast<size_t>(i)];
      b->SetLinearVelocity(b2Vec2_zero);
      b->SetAngularVelocity(0.0f);
    }
  }

  void active_particles(std::vector<ActiveParticle>& out) const override {
    out.clear();
    out.reserve(w_->active.size());
    for (int i : w_->active) out.push_back({i, w_->to_lab(w_->particles[static_cast<size_t>(i)]->GetPosition())});
  }

  void particle_motions(std::vector<ParticleMotion>& out) const override {
    out.clear();
    out.reserve(w_->active.size());
    const double to_v = w_->scale.to_lab_velocity(1.0), to_w = w_->scale.time;
    for (int i : w_->active) {
      const b2Body* b = w_->particles[static_cast<size_t>(i)];
      const b2Vec2 v = b->GetLinearVelocity();
      out.push_back({i, w_->to_lab(b->GetPosition()), sc_.particles[static_cast<size_t>(i)].diameter / 2, v.x * to_v,
                     v.y * to_v, 0.0, 0.0, 0.0, b->GetAngularVelocity() * to_w});
    }
  }

  void reinject(const std::vector<ActiveParticle>& placements) override {
    for (const ActiveParticle& p : placements) {
      b2Body* b = w_->particles.at(static_cast<size_t>(p.id));
      if (!b) throw std::logic_error("reinject: particle was retired");
      b->SetTransform(w_->to_engine(p.position), 0.0f);
      b->SetLinearVelocity(b2Vec2_zero);
      b->SetAngularVelocity(0.0f);
    }
  }

  World2D& world() { return *w_; }
  const World2D& world() const { return *w_; }

  void retire(const std::vector<int>& ids) override {
    for (int i : ids) {
      b2Body*& b = w_->particles[static_cast<size_t>(i)];
      if (b) w_->world->DestroyBody(b);  // also destroys its friction joint, if any
      b = nullptr;
    }
    std::erase_if(w_->active, [&](int i) { return w_->particles[static_cast<size_t>(i)] == nullptr; });
  }

 private:
  // Kinematic bodies move with the velocity that lands them exactly on the
  // schedule at the end of the step (Box2D integrates them as x += v dt).
  void follow(b2Body* body, b2Vec2 rest, Vec2 offset_m) {
    if (!body || body->GetType() != b2_kinematicBody) return;
    const b2Vec2 target = rest + w_->to_engine(offset_m);
    const b2Vec2 v = (1.0f / static_cast<float>(w_->dt_engine)) * (target - body->GetPosition());
    body->SetLinearVelocity(v);
  }

  const CompiledScenario& sc_;
  std::vector<std::unique_ptr<ReducedEffect2D>> effects_;
  std::unique_ptr<World2D> w_;
};


}  // namespace gapflow

// Reduced-model effects: what the top-down 2D view of spheres on a board loses,
// added back. Each effect is one small class behind ReducedEffect2D, so that a
// new effect is added in make_effects2d() without touching the stepping loop.
#pragma once

#include "common/geometry.hpp"
#include "sim2d/world2d.hpp"

#include <memory>
#include <vector>

namespace gapflow {

class ReducedEffect2D {
 public:
  virtual ~ReducedEffect2D() = default;
  virtual const char* name() const = 0;
  // Before the world is built: change how particle bodies are made.
  virtual void shape_bodies(BodyModel2D& /*model*/) const {}
  // After the world is built (create joints etc.).
  virtual void attach(World2D& /*world*/) {}
  // Before every engine step (forces; dt in engine seconds).
  virtual void before_step(World2D& /*world*/) {}
};

// Rolling without slipping: a sphere of inertia factor k = I/(m r^2) rolling on
// the board accelerates at g sin(theta)/(1+k) (5/7 g sin(theta) for k = 2/5) and
// responds to in-plane contact impulses with inertia (1+k) m once the slip has
// decayed (7/2 mu g cos(theta) ~ 8 m/s^2 at mu = 0.24: ~12 ms for 0.1 m/s).
class RollingEffect final : public ReducedEffect2D {
 public:
  explicit RollingEffect(double inertia_factor) : k_(inertia_factor) {}
  const char* name() const override { return "rolling"; }
  void shape_bodies(BodyModel2D& model) const override;

 private:
  double k_;
};

// Resistance from the board: a force mu_r m g cos(theta) against the velocity
// (rolling resistance) and a torque s m g cos(theta) against the spin about the
// board normal (spinning friction, s a length). Coulomb-like: constant magnitude,
// clamped so that it can stop a particle but never reverse it.
class BaseFrictionEffect final : public ReducedEffect2D {
 public:
  BaseFrictionEffect(BaseFrictionMethod method, double rolling_resistance, double spinning_friction_m);
  const char* name() const override { return "base_friction"; }
  void attach(World2D& world) override;
  void before_step(World2D& world) override;

 private:
  BaseFrictionMethod method_;
  double mu_r_;        // dimensionless
  double spin_len_m_;  // m (lab)
};

// Linear drag -gamma m v on the sphere's translation (air, a viscous film on the board).
// The body carries the rolling mass (1+k) m, so a sphere rolling without slipping decays
// as exp(-gamma t / (1+k)): the drag acts on m, the inertia is (1+k) m. Applied as Box2D's
// linear damping, which the solver integrates implicitly (also inside contacts) as
// v *= 1 / (1 + h c) per step; c is chosen so that this factor is exactly exp(-h gamma m / M).
class LinearDragEffect final : public ReducedEffect2D {
 public:
  explicit LinearDragEffect(double gamma_per_s) : gamma_(gamma_per_s) {}
  const char* name() const override { return "linear_drag"; }
  void attach(World2D& world) override;

 private:
  double gamma_;  // 1/s (lab)
};

// Quadratic drag -c m |v| v on the sphere's translation: a force before every step. Over one
// step it gives the exact free solution v / (1 + c' |v| h), c' = c m / M, so the
// explicit integration adds no error of order h to the drag law.
class QuadraticDragEffect final : public ReducedEffect2D {
 public:
  explicit QuadraticDragEffect(double c_per_m) : c_(c_per_m) {}
  const char* name() const override { return "quadratic_drag"; }
  void before_step(World2D& world) override;

 private:
  double c_;  // 1/m (lab)
};

std::vector<std::unique_ptr<ReducedEffect2D>> make_effects2d(const CompiledScenario& scenario);

}  // namespace gapflow

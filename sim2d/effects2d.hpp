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

// Vertical sliding friction at the in-plane contacts of spheres rolling on the board: on each
// sphere an in-plane force -lambda mu F_n sign(n.(v_i + v_j)) n (N; F_n the contact's normal
// force, mu the pair's Coulomb coefficient, lambda = model.box2d.rolling_contact in [0, 1]).
//
// Why: a sphere rolling without slipping spins at w = (z x v)/r, so its surface at the in-plane
// contact point r n moves at v_i - z (v_i.n), its partner's (at -r n) at v_j + z (v_j.n): the
// contact slides out of the board plane at u = -z n.(v_i + v_j), which a top-down disc model
// cannot see (a pushing pair rubs at 2v; head-on, or side by side, it does not). Coulomb friction
// mu F_n against that slip exerts a torque tau on each sphere that opposes its rolling spin; a
// sphere held to rolling feels a torque as the in-plane force -(z x tau)/r on its rolling mass
// (m a = F + F_b, I dw/dt = tau - r z x F_b, w = z x v / r => (1+k) m a = F - (z x tau)/r), which
// is the same vector on both spheres, with power -mu F_n |n.(v_i + v_j)|: friction times sliding
// speed. A wall or obstruction does not roll (v_j = 0, mu the wall friction). The board supplies
// that torque by its friction: a force f alone on the rolling mass needs board friction
// F_b = m a = f/(1+k), so the sum on one sphere is capped at (1+k) mu_base m g cos(theta) (beyond
// it the sphere would slip on the board; the excess is dropped). F_n is the normal impulse Box2D
// solved in the previous step over the step (a one-step lag). Neglected: the change of the board's
// normal load by the vertical friction forces (it would matter only through rolling resistance),
// and the board friction the other in-plane forces F already need (-k F/(1+k)) in the cap.
class RollingContactEffect final : public ReducedEffect2D {
 public:
  RollingContactEffect(double fraction, double friction_base, double inertia_factor)
      : lambda_(fraction), mu_base_(friction_base), k_(inertia_factor) {}
  const char* name() const override { return "rolling_contact"; }
  void before_step(World2D& world) override;

 private:
  double lambda_;                // fraction of the derived force (1 = the mechanics above)
  double mu_base_;               // particle-board Coulomb coefficient (caps the force per sphere)
  double k_;                     // I/(m r^2) of the rolling sphere
  std::vector<b2Vec2> force_;    // per particle id, this step's sum (engine N); reused
};

// The force law of RollingContactEffect for one contact: the in-plane force on EACH of the two
// spheres (the same vector on both), -mu F_n sign(s) n with s = n.(v_i + v_j). n: unit normal from
// sphere i to its partner j (in-plane); against a wall pass v_j = 0. inv_mass_sum: 1/M_i + 1/M_j
// of the bodies that carry it (1/M_i against a wall) and h the step: the magnitude is clamped so
// that over h it can stop s but never reverse it (h = 0: no clamp). Any consistent units.
Vec2 rolling_contact_force(Vec2 vi, Vec2 vj, Vec2 n, double normal_force, double mu, double inv_mass_sum,
                           double h);

std::vector<std::unique_ptr<ReducedEffect2D>> make_effects2d(const CompiledScenario& scenario);

}  // namespace gapflow

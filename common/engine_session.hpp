// The contract between the shared run driver and an engine (2D or 3D).
//
// A session is the per-run engine state (like MuJoCo's mjData), built by a
// model from a CompiledScenario (like mjModel). The driver (simulation.hpp)
// owns the time loop, the shaking schedule, measurement and stop rules, so the
// models only step physics.
#pragma once

#include "common/geometry.hpp"
#include "common/shaking.hpp"

#include <memory>
#include <string>
#include <vector>

namespace gapflow {

struct ActiveParticle {
  int id;        // particle index
  Vec2 position; // m, plane frame (lab units)
};

// Motion of one particle, for views and file writers (view/): lab units, plane frame.
// The 2D model has no z motion: z is the sphere's radius (it rests on the board) and
// only spin.z is set.
struct ParticleMotion {
  int id;           // particle index
  Vec2 position;    // m, centre in the board plane
  double z;         // m, centre height above the board plane
  double vx, vy, vz;  // m/s
  double wx, wy, wz;  // rad/s, spin
};

class EngineSession {
 public:
  virtual ~EngineSession() = default;
  virtual std::string model_name() const = 0;  // "2d" or "3d"
  virtual double time_step() const = 0;        // s (lab) advanced by one step()
  // Close or open the release barrier.
  virtual void set_barrier(bool closed) = 0;
  // Kinematic bodies must reach these offsets (m, from rest) at the end of the next step.
  virtual void set_shake_targets(const ShakeOffsets& offsets_at_end_of_step) = 0;
  // Advance by time_step().
  virtual void step() = 0;
  // Set every particle's velocity (linear and angular) to zero.
  virtual void zero_velocities() = 0;
  // Positions of the particles still simulated.
  virtual void active_particles(std::vector<ActiveParticle>& out) const = 0;
  // Positions, velocities and spins of the particles still simulated (views only: the
  // driver never calls it, so it costs nothing unless a view asks).
  virtual void particle_motions(std::vector<ParticleMotion>& out) const = 0;
  // Remove particles from the simulation (passed far below the gap, or escaped).
  virtual void retire(const std::vector<int>& ids) = 0;
  // Move particles (never retired) to new positions, at rest: clog-breaking and
  // re-injection protocols (common/protocols.hpp).
  virtual void reinject(const std::vector<ActiveParticle>& placements) = 0;
};


}  // namespace gapflow

// Session3D: the full 3D model on Bullet 3. Spheres roll on the tilted board
// between walls extruded from the CompiledScenario's polygons.
//
// World (engine units, see units.hpp): the plane frame with axes kept aligned
// (x across, y uphill, z normal to the board), lengths scaled by
// EngineScaling::froude so the nominal sphere is BulletDef.engine_diameter long,
// gravity tilted to (0, -g sin theta, -g cos theta) with g = 9.81 engine units.
// Pair materials (friction, restitution, rolling and spinning friction) are
// looked up per pair by surface kind, not combined from per-body values.
#pragma once

#include "common/engine_session.hpp"
#include "common/units.hpp"

#include <memory>
#include <vector>

class btRigidBody;

namespace gapflow {

// The kind of surface a body presents; pair materials are looked up by kind.
enum class Surface3D : int { particle = 0, board = 1, wall = 2 };

// A 3D vector in lab units, plane frame (m, m/s or rad/s).
struct Vec3Lab {
  double x = 0, y = 0, z = 0;
};

// Material values of one contact pair, in lab units.
struct PairMaterial3D {
  double friction = 0;         // Coulomb coefficient
  double restitution = 0;      // coefficient of restitution
  double rolling_friction = 0; // m: rolling torque cap / normal force (Bullet's rolling friction)
  double spinning_friction = 0;// m: torsional torque cap / normal force
};

// How the session set Bullet's solver up, and the rows of its last solve (for tests).
struct SolverSetup3D {
  bool split_islands = true;      // islands solved separately (only sleeping needs it)
  int bodies_that_may_sleep = 0;  // dynamic and kinematic bodies whose deactivation is not disabled
  int gyroscopic_spheres = 0;     // spheres with one of Bullet's gyroscopic flags
  int rolling_rows = 0;           // rolling and spinning rows solved in the last step()
  int dropped_rolling_rows = 0;   // rows capped at zero (or the rolling floor) left out in the last step()
  int skipped_far_pairs = 0;      // sphere-box narrow phases skipped in the last step() (certainly apart)
};

// Shortcuts that must leave a run the same bit for bit (on by default; tests turn
// them off to check exactly that).
struct Shortcuts3D {
  bool drop_idle_rolling_rows = true;     // rolling/spinning rows capped at zero (Solver3D)
  bool skip_far_sphere_box_pairs = true;  // narrow phase of a sphere and a box certainly apart (Dispatcher3D)
};

// One contact point as the solver sees it (for tests and diagnostics).
struct ContactInfo3D {
  Surface3D a = Surface3D::particle, b = Surface3D::particle;  // a is always a particle
  int particle_a = -1, particle_b = -1;  // particle ids (-1 when not a particle)
  PairMaterial3D material;               // the values Bullet combined for this point
  double distance = 0;                   // m, negative = penetration
};

class Session3D final : public EngineSession {
 public:
  explicit Session3D(const CompiledScenario& scenario);
  ~Session3D() override;
  Session3D(const Session3D&) = delete;
  Session3D& operator=(const Session3D&) = delete;

  // EngineSession.
  std::string model_name() const override { return "3d"; }
  double time_step() const override;
  void set_barrier(bool closed) override;
  void set_shake_targets(const ShakeOffsets& offsets_at_end_of_step) override;
  void step() override;
  void zero_velocities() override;
  void active_particles(std::vector<ActiveParticle>& out) const override;
  void particle_motions(std::vector<ParticleMotion>& out) const override;
  void retire(const std::vector<int>& ids) override;
  void reinject(const std::vector<ActiveParticle>& placements) override;

  // --- Extras for tests and diagnostics (lab units, plane frame) ---
  const EngineScaling& scaling() const;
  int body_count() const;          // rigid bodies in the world (particles, walls, board, barrier)
  int particle_count() const;      // particles still simulated
  bool is_active(int id) const;
  Vec3Lab position(int id) const;          // m, centre of the sphere
  Vec3Lab velocity(int id) const;          // m/s
  Vec3Lab angular_velocity(int id) const;  // rad/s
  double radius(int id) const;             // m
  // Place a particle (centre, m) with a velocity (m/s) and no spin.
  void place(int id, Vec3Lab centre, Vec3Lab velocity = {});
  // The pair values the session asks Bullet to use (lab units). For two
  // particles, ids give the radii; otherwise particle_b is ignored.
  PairMaterial3D pair_material(Surface3D other, int particle_a, int particle_b = -1) const;
  // Every current contact point, with the values Bullet actually combined.
  std::vector<ContactInfo3D> contacts() const;
  // Kinematic body positions (m, plane frame offset from rest) for tests of shaking.
  Vec2 bottleneck_offset(bool right) const;
  Vec2 obstruction_offset() const;
  SolverSetup3D solver_setup() const;
  void set_shortcuts(const Shortcuts3D& shortcuts);  // tests only
  double time() const;  // s (lab) simulated so far by step()

  struct World;  // opaque: the Bullet objects (session3d.cpp)

 private:
  std::unique_ptr<World> w_;
};

std::unique_ptr<EngineSession> make_session_3d(const CompiledScenario& scenario);

}  // namespace gapflow

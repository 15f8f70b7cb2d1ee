// Session3D: builds a Bullet world from a CompiledScenario and steps it.
//
// Sections: bodies, the session's stages (build, step, report, retire, reinject) and the
// test extras. The shapes (prisms extruded from the plane-frame polygons) are in prisms3d.cpp,
// the materials and Bullet's combiner hooks in materials3d.cpp.
#include "sim3d/session3d.hpp"

#include "sim3d/model3d.hpp"
#include "sim3d/far_pairs.hpp"
#include "sim3d/materials3d.hpp"
#include "sim3d/prisms3d.hpp"
#include "sim3d/solver3d.hpp"

#include <btBulletDynamicsCommon.h>
#include <BulletCollision/CollisionDispatch/btSimulationIslandManager.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace gapflow {

// Types live in a named namespace: Session3D::World (external linkage) holds them.
namespace bullet3d {

// Engine mass of a sphere of the nominal diameter. Only mass ratios matter
// (walls and board are immovable), but Bullet caps the rolling/spinning torque
// impulse at rf * min(normal impulse, 1) (btSequentialImpulseConstraintSolver),
// so impulses must stay far below 1: with 1e-3 a pile of 10^4 spheres leaning
// on one contact still gives ~0.3 per step.
constexpr double kNominalMass = 1e-3;

// Moves a kinematic body: Bullet reads this at the start of each stepSimulation,
// places the body there and gives it the velocity (target - previous) / dt.
struct KinematicMotion : btMotionState {
  btTransform target;
  void getWorldTransform(btTransform& t) const override { t = target; }
  void setWorldTransform(const btTransform&) override {}  // Bullet never drives a kinematic body
};

// ---------------------------------------------------------------------------
// World
// ---------------------------------------------------------------------------

struct KinematicBody {
  std::unique_ptr<btCollisionShape> shape;
  std::unique_ptr<KinematicMotion> motion;
  std::unique_ptr<btRigidBody> body;
  btTransform rest;
  Vec2 offset_from{};  // m, offset at the start of the current step
};

}  // namespace bullet3d

struct Session3D::World {
  // Copied scenario values (the session does not keep a reference to the scenario).
  EngineScaling scale;
  double time_step_lab = 0;  // s
  int substeps = 1;
  double dt_engine = 0;      // engine s per substep
  double nominal_d = 0;      // m
  double time_lab = 0;       // s, advanced by step()
  bool sleeping = false;
  bullet3d::MaterialTable materials;
  ShakeOffsets target{};
  double linear_damping = 0;  // Bullet's linear damping of every sphere (particles.drag_per_s)
  double quadratic_drag = 0;  // 1/(engine length), particles.quadratic_drag_per_m

  // Bullet objects; the world must be destroyed after every body is removed (see ~World).
  btDefaultCollisionConfiguration config;
  bullet3d::Dispatcher3D dispatcher{&config};  // skips the narrow phase of pairs certainly apart
  btDbvtBroadphase broadphase;
  bullet3d::Solver3D solver;  // Bullet's solver without the rolling rows that cannot act
  btDiscreteDynamicsWorld world{&dispatcher, &broadphase, &solver, &config};

  std::vector<std::unique_ptr<btCollisionShape>> static_shapes;
  std::vector<std::unique_ptr<btRigidBody>> static_bodies;  // board, retaining walls, top wall
  std::unique_ptr<btCollisionShape> barrier_shape;
  std::unique_ptr<btRigidBody> barrier;
  bool barrier_in_world = false;
  bullet3d::KinematicBody left_wall, right_wall, obstruction;
  bool has_obstruction = false;
  std::vector<std::unique_ptr<btSphereShape>> sphere_shapes;
  std::vector<std::unique_ptr<btRigidBody>> particles;  // index = particle id; null once retired
  int alive = 0;

  ~World() {
    for (int i = world.getNumCollisionObjects() - 1; i >= 0; --i)
      world.removeCollisionObject(world.getCollisionObjectArray()[i]);
  }

  void tag(btRigidBody& b, Surface3D kind, int id) {
    b.setUserIndex(static_cast<int>(kind));
    b.setUserIndex2(id);
    b.setUserIndex3(bullet3d::kSessionBodyTag);
    b.setUserPointer(&materials);
  }
};

namespace {

using namespace bullet3d;
using World3D = Session3D::World;

// --- Build stages ------------------------------------------------------------

void configure_world(World3D& w, const CompiledScenario& sc) {
  const BulletDef& b = sc.def.model.bullet;
  w.scale = EngineScaling::froude(sc.nominal_diameter, b.engine_diameter);
  w.time_step_lab = b.time_step_s;
  w.substeps = b.substeps;
  w.dt_engine = w.scale.to_engine_time(b.time_step_s) / b.substeps;
  w.nominal_d = sc.nominal_diameter;
  w.sleeping = b.sleeping;
  w.materials = make_materials(sc.def.particles, w.scale);
  // Rolling rows capped at the floor exist only so that Bullet builds the spinning row.
  w.solver.set_negligible_cap(btScalar(w.materials.rolling_floor));

  // Tilted gravity, axis-aligned geometry: Froude scaling keeps g = 9.81 engine units.
  const double g = w.scale.to_engine_acceleration(kStandardGravity);
  // A lateral tilt phi (plane.lateral_tilt_deg) rolls the board about its fall line.
  const double th = sc.incline, phi = sc.lateral_tilt;
  w.world.setGravity(btVector3(g * std::cos(th) * std::sin(phi), -g * std::sin(th), -g * std::cos(th) * std::cos(phi)));
  // Drag on the spheres' translation. Bullet damps v *= (1 - c)^dt (btRigidBody::applyDamping,
  // before the constraints): c = 1 - exp(-gamma) gives exactly exp(-gamma dt).
  w.linear_damping = -std::expm1(-w.scale.to_engine_rate(sc.def.particles.drag_per_s));
  w.quadratic_drag = sc.def.particles.quadratic_drag_per_m / w.scale.length;  // 1/(engine length)

  btContactSolverInfo& info = w.world.getSolverInfo();
  info.m_numIterations = b.solver_iterations;
  // Two friction directions per contact: with one, a sphere rolling without slip
  // (zero contact velocity) gets an arbitrary single direction and can slip sideways.
  info.m_solverMode |= SOLVER_USE_2_FRICTION_DIRECTIONS;
  const double d_e = b.engine_diameter;
  const double v_ref = std::sqrt(g * d_e);  // engine velocity scale sqrt(g d)
  // Slower impacts are inelastic (Bullet's default 0.2 is in engine m/s; tie it to the grain scale).
  info.m_restitutionVelocityThreshold = 0.05 * v_ref;
  // Split impulse (on by default) resolves penetration deeper than this without adding energy.
  info.m_splitImpulsePenetrationThreshold = -0.04 * d_e;
  // Islands only serve sleeping: Bullet puts an island to sleep as a whole and skips
  // it. With sleeping off no body can sleep (every sphere and kinematic wall is
  // DISABLE_DEACTIVATION, static bodies are never solved), so every island would be
  // solved anyway: one group of all contacts spares sorting the manifolds by island
  // every step (btSimulationIslandManager::processIslands).
  w.world.getSimulationIslandManager()->setSplitIslands(w.sleeping);
}

void add_static(World3D& w, PlacedShape placed, Surface3D kind) {
  btRigidBody::btRigidBodyConstructionInfo ci(0, nullptr, placed.shape.get());
  ci.m_startWorldTransform = placed.pose;
  auto body = std::make_unique<btRigidBody>(ci);
  w.tag(*body, kind, -1);
  w.world.addRigidBody(body.get());
  w.static_shapes.push_back(std::move(placed.shape));
  w.static_bodies.push_back(std::move(body));
}

void add_board(World3D& w) {
  // The board is the half-space z <= 0, unbounded: a sphere that leaves over a
  // wall keeps rolling and the gap monitor sees it cross y = 0 outside the gap.
  PlacedShape board;
  board.shape = std::make_unique<btStaticPlaneShape>(btVector3(0, 0, 1), 0);
  board.pose.setIdentity();
  add_static(w, std::move(board), Surface3D::board);
}

// A cover plate parallel to the board at plane.cover_gap_mm (the glass front of a
// quasi-2D cell): the half-space z >= h, unbounded like the board and made of the
// same material (board friction, rolling resistance).
void add_cover(World3D& w, const CompiledScenario& sc) {
  if (sc.def.plane.cover_gap_mm <= 0) return;
  const double h = w.scale.to_engine_length(sc.def.plane.cover_gap_mm * 1e-3);
  PlacedShape cover;
  cover.shape = std::make_unique<btStaticPlaneShape>(btVector3(0, 0, -1), static_cast<btScalar>(-h));
  cover.pose.setIdentity();
  add_static(w, std::move(cover), Surface3D::board);
}

void make_kinematic(World3D& w, KinematicBody& k, PlacedShape placed) {
  k.rest = placed.pose;
  k.motion = std::make_unique<KinematicMotion>();
  k.motion->target = k.rest;
  k.shape = std::move(placed.shape);
  btRigidBody::btRigidBodyConstructionInfo ci(0, k.motion.get(), k.shape.get());
  k.body = std::make_unique<btRigidBody>(ci);
  k.body->setCollisionFlags(k.body->getCollisionFlags() | btCollisionObject::CF_KINEMATIC_OBJECT);
  k.body->setActivationState(DISABLE_DEACTIVATION);
  w.tag(*k.body, Surface3D::wall, -1);
  w.world.addRigidBody(k.body.get());
}

void add_walls(World3D& w, const CompiledScenario& sc) {
  const BulletDef& b = sc.def.model.bullet;
  const double d_e = b.engine_diameter;
  const double z0 = -d_e, z1 = b.wall_height_d * d_e;  // walls reach below the board: no seam at the foot
  const double margin = b.collision_margin_d * d_e;
  auto prism = [&](const ConvexPolygon& p) { return make_prism(to_engine(p, w.scale), z0, z1, margin); };
  add_static(w, prism(sc.left_retaining_wall), Surface3D::wall);
  add_static(w, prism(sc.right_retaining_wall), Surface3D::wall);
  add_static(w, prism(sc.top_wall), Surface3D::wall);
  make_kinematic(w, w.left_wall, prism(sc.left_bottleneck_wall));
  make_kinematic(w, w.right_wall, prism(sc.right_bottleneck_wall));

  PlacedShape barrier = prism(sc.barrier);
  btRigidBody::btRigidBodyConstructionInfo ci(0, nullptr, barrier.shape.get());
  ci.m_startWorldTransform = barrier.pose;
  w.barrier_shape = std::move(barrier.shape);
  w.barrier = std::make_unique<btRigidBody>(ci);
  w.tag(*w.barrier, Surface3D::wall, -1);
}

void add_obstruction(World3D& w, const CompiledScenario& sc) {
  const ObstructionGeometry& g = sc.obstruction;
  if (g.shape == ObstructionShape::none) return;
  const BulletDef& b = sc.def.model.bullet;
  const double d_e = b.engine_diameter;
  const double z0 = -d_e, z1 = b.wall_height_d * d_e, margin = b.collision_margin_d * d_e;
  PlacedShape placed;
  if (g.shape == ObstructionShape::cylinder) {
    const double R = w.scale.to_engine_length(g.circle.radius);
    auto cyl = std::make_unique<btCylinderShapeZ>(btVector3(R, R, (z1 - z0) / 2));
    cyl->setMargin(margin);  // like boxes, cylinders keep their outer size
    placed.shape = std::move(cyl);
    placed.pose.setIdentity();
    placed.pose.setOrigin(btVector3(w.scale.to_engine_length(g.circle.centre.x),
                                    w.scale.to_engine_length(g.circle.centre.y), (z0 + z1) / 2));
  } else if (g.corner_radius > 0) {
    // Rounded corners (obstruction.corner_radius_mm): the compiled polygon is the core, the
    // rounding radius r becomes the hull's margin; a margin above r rounds further, so
    // then the core is moved in by the difference first.
    const double r = w.scale.to_engine_length(g.corner_radius), rounding = std::max(r, margin);
    const ConvexPolygon core = inward_offset(g.polygon, w.scale.to_lab_length(rounding - r));
    const std::vector<Point2> core_e = to_engine(core, w.scale);
    placed = hull_prism(prism_at(core_e, z0, z1), core_e, z0, z1, rounding);
  } else {
    placed = make_prism(to_engine(g.polygon, w.scale), z0, z1, margin);
  }
  make_kinematic(w, w.obstruction, std::move(placed));
  w.has_obstruction = true;
}

void add_particles(World3D& w, const CompiledScenario& sc) {
  const double lin = 0.01 * std::sqrt(kStandardGravity * sc.def.model.bullet.engine_diameter);
  for (size_t i = 0; i < sc.particles.size(); ++i) {
    const ParticleSeed& seed = sc.particles[i];
    const double r = w.scale.to_engine_length(seed.diameter / 2);
    auto shape = std::make_unique<btSphereShape>(r);  // margin = radius: the sphere is exact
    const double ratio = seed.diameter / sc.nominal_diameter;
    const double mass = kNominalMass * ratio * ratio * ratio;  // same density for all spheres
    btVector3 inertia;
    shape->calculateLocalInertia(mass, inertia);  // 2/5 m r^2
    btRigidBody::btRigidBodyConstructionInfo ci(mass, nullptr, shape.get(), inertia);
    ci.m_linearDamping = w.linear_damping;
    ci.m_startWorldTransform.setIdentity();
    ci.m_startWorldTransform.setOrigin(btVector3(w.scale.to_engine_length(seed.position.x),
                                                 w.scale.to_engine_length(seed.position.y), r));
    auto body = std::make_unique<btRigidBody>(ci);
    w.tag(*body, Surface3D::particle, static_cast<int>(i));
    // A sphere's inertia is isotropic, so its gyroscopic torque w x (I w) is exactly zero.
    // Bullet's default implicit gyroscopic step (btRigidBody's BT_ENABLE_GYROSCOPIC_FORCE_
    // IMPLICIT_BODY) would only add round-off (w is rotated into the body frame and back)
    // for a 3x3 solve per sphere and step.
    body->setFlags(body->getFlags() & ~BT_ENABLE_GYROSCOPIC_FORCE_IMPLICIT_BODY);
    if (w.sleeping) {
      body->setSleepingThresholds(lin, lin / r);  // scaled to the grain: ~1 % of sqrt(g d)
    } else {
      body->setActivationState(DISABLE_DEACTIVATION);  // Bullet's defaults would freeze slow flow
    }
    w.world.addRigidBody(body.get());
    w.sphere_shapes.push_back(std::move(shape));
    w.particles.push_back(std::move(body));
  }
  w.alive = static_cast<int>(sc.particles.size());
}

// --- Step stages -------------------------------------------------------------

// Quadratic drag -c m |v| v at each sphere's centre, for the coming Bullet step (Bullet
// clears forces after every step). Explicit: relative error ~ c |v| dt per unit c |v| t.
void apply_quadratic_drag(World3D& w) {
  if (w.quadratic_drag <= 0) return;
  for (auto& p : w.particles) {
    if (!p) continue;
    const btVector3 v = p->getLinearVelocity();
    p->applyCentralForce(-w.quadratic_drag / p->getInvMass() * v.length() * v);
  }
}

Vec2 lerp(Vec2 a, Vec2 b, double f) { return {a.x + (b.x - a.x) * f, a.y + (b.y - a.y) * f}; }

void place_kinematic(const World3D& w, KinematicBody& k, Vec2 offset) {
  if (!k.body) return;
  btTransform t = k.rest;
  t.setOrigin(t.getOrigin() +
              btVector3(w.scale.to_engine_length(offset.x), w.scale.to_engine_length(offset.y), 0));
  k.motion->target = t;
}

btRigidBody& particle(const World3D& w, int id) {
  if (id < 0 || id >= static_cast<int>(w.particles.size()) || !w.particles[id])
    throw std::out_of_range("Session3D: no active particle " + std::to_string(id));
  return *w.particles[id];
}

Vec3Lab scaled(const btVector3& v, double factor) { return {v.x() * factor, v.y() * factor, v.z() * factor}; }

}  // namespace

// ---------------------------------------------------------------------------
// Session
// ---------------------------------------------------------------------------

Session3D::Session3D(const CompiledScenario& scenario) : w_(std::make_unique<World>()) {
  install_combiner_hooks();
  configure_world(*w_, scenario);
  add_board(*w_);
  add_cover(*w_, scenario);
  add_walls(*w_, scenario);
  add_obstruction(*w_, scenario);
  add_particles(*w_, scenario);
}

Session3D::~Session3D() = default;

double Session3D::time_step() const { return w_->time_step_lab; }

void Session3D::set_barrier(bool closed) {
  if (closed == w_->barrier_in_world) return;
  if (closed) {
    w_->world.addRigidBody(w_->barrier.get());
  } else {
    w_->world.removeRigidBody(w_->barrier.get());
  }
  w_->barrier_in_world = closed;
}

void Session3D::set_shake_targets(const ShakeOffsets& offsets_at_end_of_step) {
  w_->target = offsets_at_end_of_step;
}

// One step = `substeps` Bullet steps of fixed length. Kinematic bodies are moved
// along a straight line so that they sit exactly on the target at the end.
void Session3D::step() {
  World& w = *w_;
  const ShakeOffsets& to = w.target;
  w.solver.reset_counts();
  w.dispatcher.reset_counts();
  for (int s = 1; s <= w.substeps; ++s) {
    const double f = static_cast<double>(s) / w.substeps;
    // Stage 1: where the kinematic bodies must be at the end of this substep.
    place_kinematic(w, w.left_wall, lerp(w.left_wall.offset_from, to.left_wall, f));
    place_kinematic(w, w.right_wall, lerp(w.right_wall.offset_from, to.right_wall, f));
    place_kinematic(w, w.obstruction, lerp(w.obstruction.offset_from, to.obstruction, f));
    apply_quadratic_drag(w);
    // Stage 2: integrate. maxSubSteps = 0 makes Bullet step exactly dt (no
    // fixed-step accumulator that could drop or add time).
    w.world.stepSimulation(btScalar(w.dt_engine), 0, btScalar(w.dt_engine));
  }
  // Stage 3: bookkeeping.
  w.left_wall.offset_from = to.left_wall;
  w.right_wall.offset_from = to.right_wall;
  w.obstruction.offset_from = to.obstruction;
  w.time_lab += w.time_step_lab;
}

void Session3D::zero_velocities() {
  for (auto& p : w_->particles) {
    if (!p) continue;
    p->setLinearVelocity(btVector3(0, 0, 0));
    p->setAngularVelocity(btVector3(0, 0, 0));
  }
}

// Every simulated sphere is reported, also one below the board (z < -d) or
// outside the walls: the gap monitor decides what an escape is.
void Session3D::active_particles(std::vector<ActiveParticle>& out) const {
  out.clear();
  out.reserve(w_->alive);
  const double to_m = 1.0 / w_->scale.length;
  for (size_t i = 0; i < w_->particles.size(); ++i) {
    const btRigidBody* p = w_->particles[i].get();
    if (!p) continue;
    const btVector3& o = p->getCenterOfMassPosition();
    out.push_back({static_cast<int>(i), {o.x() * to_m, o.y() * to_m}});
  }
}

void Session3D::particle_motions(std::vector<ParticleMotion>& out) const {
  out.clear();
  out.reserve(w_->alive);
  for (size_t i = 0; i < w_->particles.size(); ++i) {
    if (!w_->particles[i]) continue;
    const int id = static_cast<int>(i);
    const Vec3Lab x = position(id), v = velocity(id), w = angular_velocity(id);
    out.push_back({id, {x.x, x.y}, x.z, v.x, v.y, v.z, w.x, w.y, w.z});
  }
}

void Session3D::retire(const std::vector<int>& ids) {
  for (int id : ids) {
    if (id < 0 || id >= static_cast<int>(w_->particles.size()) || !w_->particles[id]) continue;
    w_->world.removeRigidBody(w_->particles[id].get());
    w_->particles[id].reset();
    w_->sphere_shapes[id].reset();
    --w_->alive;
  }
}

// Teleport to (x, y) on the board, at rest. The body's old contact caches are
// dropped so that no warm-start impulse from the old place is applied.
void Session3D::reinject(const std::vector<ActiveParticle>& placements) {
  for (const ActiveParticle& p : placements) {
    btRigidBody& b = particle(*w_, p.id);
    const double r = w_->scale.to_lab_length(sphere_radius(&b));
    place(p.id, {p.position.x, p.position.y, r});
    w_->world.getBroadphase()->getOverlappingPairCache()->cleanProxyFromPairs(b.getBroadphaseHandle(),
                                                                             w_->world.getDispatcher());
  }
}

// --- Extras ------------------------------------------------------------------

const EngineScaling& Session3D::scaling() const { return w_->scale; }
int Session3D::body_count() const { return w_->world.getNumCollisionObjects(); }
int Session3D::particle_count() const { return w_->alive; }
double Session3D::time() const { return w_->time_lab; }

bool Session3D::is_active(int id) const {
  return id >= 0 && id < static_cast<int>(w_->particles.size()) && w_->particles[id] != nullptr;
}

Vec3Lab Session3D::position(int id) const {
  return scaled(particle(*w_, id).getCenterOfMassPosition(), 1.0 / w_->scale.length);
}
Vec3Lab Session3D::velocity(int id) const {
  return scaled(particle(*w_, id).getLinearVelocity(), w_->scale.to_lab_velocity(1.0));
}
Vec3Lab Session3D::angular_velocity(int id) const {
  // rad per engine second -> rad per lab second: one lab second is `time` engine seconds.
  return scaled(particle(*w_, id).getAngularVelocity(), w_->scale.time);
}
double Session3D::radius(int id) const {
  return w_->scale.to_lab_length(sphere_radius(&particle(*w_, id)));
}

void Session3D::place(int id, Vec3Lab c, Vec3Lab v) {
  btRigidBody& b = particle(*w_, id);
  const EngineScaling& s = w_->scale;
  btTransform t;
  t.setIdentity();
  t.setOrigin(btVector3(s.to_engine_length(c.x), s.to_engine_length(c.y), s.to_engine_length(c.z)));
  b.setWorldTransform(t);
  b.setInterpolationWorldTransform(t);
  b.setLinearVelocity(btVector3(s.to_engine_velocity(v.x), s.to_engine_velocity(v.y), s.to_engine_velocity(v.z)));
  b.setAngularVelocity(btVector3(0, 0, 0));
  b.setInterpolationLinearVelocity(b.getLinearVelocity());
  b.setInterpolationAngularVelocity(btVector3(0, 0, 0));
  b.clearForces();
  b.activate(true);
}

PairMaterial3D Session3D::pair_material(Surface3D other, int a, int b) const {
  const double ra = sphere_radius(&particle(*w_, a));
  const double rb = other == Surface3D::particle ? sphere_radius(&particle(*w_, b)) : 0.0;
  const PairEngine p = pair_values(w_->materials, Surface3D::particle, ra, other, rb);
  const EngineScaling& s = w_->scale;
  return {p.friction, p.restitution, s.to_lab_length(p.rolling), s.to_lab_length(p.spinning)};
}

std::vector<ContactInfo3D> Session3D::contacts() const {
  std::vector<ContactInfo3D> out;
  const EngineScaling& s = w_->scale;
  btDispatcher& d = const_cast<bullet3d::Dispatcher3D&>(w_->dispatcher);
  for (int m = 0; m < d.getNumManifolds(); ++m) {
    const btPersistentManifold* man = d.getManifoldByIndexInternal(m);
    const btCollisionObject* a = man->getBody0();
    const btCollisionObject* b = man->getBody1();
    if (kind_of(a) != Surface3D::particle) std::swap(a, b);
    for (int k = 0; k < man->getNumContacts(); ++k) {
      const btManifoldPoint& cp = man->getContactPoint(k);
      ContactInfo3D c;
      c.a = kind_of(a);
      c.b = kind_of(b);
      c.particle_a = c.a == Surface3D::particle ? a->getUserIndex2() : -1;
      c.particle_b = c.b == Surface3D::particle ? b->getUserIndex2() : -1;
      c.material = {cp.m_combinedFriction, cp.m_combinedRestitution, s.to_lab_length(cp.m_combinedRollingFriction),
                    s.to_lab_length(cp.m_combinedSpinningFriction)};
      c.distance = s.to_lab_length(cp.getDistance());
      out.push_back(c);
    }
  }
  return out;
}

Vec2 Session3D::bottleneck_offset(bool right) const {
  const KinematicBody& k = right ? w_->right_wall : w_->left_wall;
  const btVector3 d = k.body->getWorldTransform().getOrigin() - k.rest.getOrigin();
  return {w_->scale.to_lab_length(d.x()), w_->scale.to_lab_length(d.y())};
}

Vec2 Session3D::obstruction_offset() const {
  if (!w_->has_obstruction) return {};
  const KinematicBody& k = w_->obstruction;
  const btVector3 d = k.body->getWorldTransform().getOrigin() - k.rest.getOrigin();
  return {w_->scale.to_lab_length(d.x()), w_->scale.to_lab_length(d.y())};
}

SolverSetup3D Session3D::solver_setup() const {
  const World& w = *w_;
  SolverSetup3D out;
  out.split_islands = const_cast<btDiscreteDynamicsWorld&>(w.world).getSimulationIslandManager()->getSplitIslands();
  const btCollisionObjectArray& objects = w.world.getCollisionObjectArray();
  for (int i = 0; i < objects.size(); ++i) {
    const btCollisionObject* o = objects[i];
    if (!o->isStaticObject() && o->getActivationState() != DISABLE_DEACTIVATION) ++out.bodies_that_may_sleep;
  }
  constexpr int gyroscopic = BT_ENABLE_GYROSCOPIC_FORCE_EXPLICIT | BT_ENABLE_GYROSCOPIC_FORCE_IMPLICIT_WORLD |
                             BT_ENABLE_GYROSCOPIC_FORCE_IMPLICIT_BODY;
  for (const auto& p : w.particles)
    if (p && (p->getFlags() & gyroscopic)) ++out.gyroscopic_spheres;
  out.rolling_rows = w.solver.rolling_rows();
  out.dropped_rolling_rows = w.solver.dropped_rows();
  out.skipped_far_pairs = static_cast<int>(w.dispatcher.skipped_pairs());
  return out;
}

void Session3D::set_shortcuts(const Shortcuts3D& s) {
  w_->solver.set_negligible_cap(s.drop_idle_rolling_rows ? btScalar(w_->materials.rolling_floor) : btScalar(-1));
  w_->dispatcher.set_skip_far_pairs(s.skip_far_sphere_box_pairs);
}

std::unique_ptr<EngineSession> make_session_3d(const CompiledScenario& scenario) {
  return std::make_unique<Session3D>(scenario);
}

}  // namespace gapflow

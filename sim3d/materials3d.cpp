#include "sim3d/materials3d.hpp"

#include <btBulletDynamicsCommon.h>
#include <BulletCollision/CollisionDispatch/btManifoldResult.h>

#include <mutex>

namespace gapflow::bullet3d {

namespace {

// Radius of the sphere rolling on the board, 0 for any other pair: the
// scenario's rolling_resistance is resistance from the board (as in the 2D
// model), and skipping it elsewhere saves Bullet three solver rows per contact.
double board_rolling_radius(Surface3D ka, double ra, Surface3D kb, double rb) {
  if (ka == Surface3D::particle && kb == Surface3D::board) return ra;
  if (kb == Surface3D::particle && ka == Surface3D::board) return rb;
  return 0.0;
}

const MaterialTable* table_of(const btCollisionObject* a, const btCollisionObject* b) {
  if (a->getUserIndex3() != kSessionBodyTag || b->getUserIndex3() != kSessionBodyTag) return nullptr;
  return static_cast<const MaterialTable*>(a->getUserPointer());
}

PairEngine pair_of(const MaterialTable& t, const btCollisionObject* a, const btCollisionObject* b) {
  return pair_values(t, kind_of(a), sphere_radius(a), kind_of(b), sphere_radius(b));
}

// Bullet's combiner hooks (btManifoldResult.h), called when a contact point is
// created. They replace the product rules (mu_a mu_b, e_a e_b, rf_a mu_b + rf_b mu_a)
// that cannot express an arbitrary pair table (e.g. mu_pp = 0 with mu_pw > 0).
btScalar combined_friction(const btCollisionObject* a, const btCollisionObject* b) {
  const MaterialTable* t = table_of(a, b);
  return t ? btScalar(pair_of(*t, a, b).friction) : btManifoldResult::calculateCombinedFriction(a, b);
}
btScalar combined_restitution(const btCollisionObject* a, const btCollisionObject* b) {
  const MaterialTable* t = table_of(a, b);
  return t ? btScalar(pair_of(*t, a, b).restitution) : btManifoldResult::calculateCombinedRestitution(a, b);
}
btScalar combined_rolling(const btCollisionObject* a, const btCollisionObject* b) {
  const MaterialTable* t = table_of(a, b);
  return t ? btScalar(pair_of(*t, a, b).rolling) : btManifoldResult::calculateCombinedRollingFriction(a, b);
}
btScalar combined_spinning(const btCollisionObject* a, const btCollisionObject* b) {
  const MaterialTable* t = table_of(a, b);
  return t ? btScalar(pair_of(*t, a, b).spinning) : btManifoldResult::calculateCombinedSpinningFriction(a, b);
}

}  // namespace

Surface3D kind_of(const btCollisionObject* o) { return static_cast<Surface3D>(o->getUserIndex()); }

double sphere_radius(const btCollisionObject* o) {
  const btCollisionShape* s = o->getCollisionShape();
  if (s->getShapeType() != SPHERE_SHAPE_PROXYTYPE) return 0;
  return static_cast<const btSphereShape*>(s)->getRadius();
}

PairEngine pair_values(const MaterialTable& t, Surface3D ka, double ra, Surface3D kb, double rb) {
  PairEngine p{};
  p.friction = t.friction[static_cast<int>(ka)][static_cast<int>(kb)];
  p.restitution = t.restitution;
  p.rolling = t.rolling_resistance * board_rolling_radius(ka, ra, kb, rb);
  p.spinning = t.spinning;
  if (p.rolling <= 0 && p.spinning > 0) p.rolling = t.rolling_floor;
  return p;
}

MaterialTable make_materials(const ParticlesDef& p, const EngineScaling& s) {
  MaterialTable t;
  const int P = static_cast<int>(Surface3D::particle), B = static_cast<int>(Surface3D::board),
            W = static_cast<int>(Surface3D::wall);
  t.friction[P][P] = p.friction_particle;
  t.friction[P][W] = t.friction[W][P] = p.friction_wall;
  t.friction[P][B] = t.friction[B][P] = p.friction_base;
  t.restitution = p.restitution;
  t.rolling_resistance = p.rolling_resistance;
  t.spinning = s.to_engine_length(mm_to_m(p.spinning_friction_mm));
  t.rolling_floor = 1e-12 * s.length;  // a rolling torque far below anything measurable
  return t;
}

// The hooks are process globals; they are stateless (the table comes from the
// bodies), so installing them once serves every session, also in parallel runs.
void install_combiner_hooks() {
  static std::once_flag once;
  std::call_once(once, [] {
    gCalculateCombinedFrictionCallback = &combined_friction;
    gCalculateCombinedRestitutionCallback = &combined_restitution;
    gCalculateCombinedRollingFrictionCallback = &combined_rolling;
    gCalculateCombinedSpinningFrictionCallback = &combined_spinning;
  });
}

}  // namespace gapflow::bullet3d

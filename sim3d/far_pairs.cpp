#include "sim3d/far_pairs.hpp"

#include <cmath>

namespace gapflow::bullet3d {

Dispatcher3D::Dispatcher3D(btCollisionConfiguration* config) : btCollisionDispatcher(config) {
  setNearCallback(&Dispatcher3D::near_callback);
}

bool sphere_far_from_box(const btCollisionObject& sphere, const btCollisionObject& box, btScalar threshold) {
  const auto* s = static_cast<const btSphereShape*>(sphere.getCollisionShape());
  const auto* b = static_cast<const btBoxShape*>(box.getCollisionShape());
  const btVector3 local = box.getWorldTransform().invXform(sphere.getWorldTransform().getOrigin());
  const btVector3 h = b->getHalfExtentsWithMargin();
  const btScalar qx = std::max(std::abs(local.x()) - h.x(), btScalar(0));
  const btScalar qy = std::max(std::abs(local.y()) - h.y(), btScalar(0));
  const btScalar qz = std::max(std::abs(local.z()) - h.z(), btScalar(0));
  const btScalar reach = 2 * s->getRadius() + threshold;
  return qx * qx + qy * qy + qz * qz > reach * reach;
}

namespace {

// The pair's manifold when it exists and holds no contact point, else null.
// `manifolds` is scratch space (kept by the dispatcher: no allocation per pair).
const btPersistentManifold* empty_manifold(const btBroadphasePair& pair, btManifoldArray& manifolds) {
  if (!pair.m_algorithm) return nullptr;  // first call: Bullet creates the manifold
  manifolds.resize(0);
  pair.m_algorithm->getAllContactManifolds(manifolds);
  if (manifolds.size() != 1 || manifolds[0]->getNumContacts() != 0) return nullptr;
  return manifolds[0];
}

}  // namespace

void Dispatcher3D::near_callback(btBroadphasePair& pair, btCollisionDispatcher& dispatcher, const btDispatcherInfo& info) {
  auto& self = static_cast<Dispatcher3D&>(dispatcher);
  if (self.skip_far_pairs_) {
    const auto* a = static_cast<const btCollisionObject*>(pair.m_pProxy0->m_clientObject);
    const auto* b = static_cast<const btCollisionObject*>(pair.m_pProxy1->m_clientObject);
    const int ta = a->getCollisionShape()->getShapeType(), tb = b->getCollisionShape()->getShapeType();
    const btCollisionObject* sphere = ta == SPHERE_SHAPE_PROXYTYPE ? a : tb == SPHERE_SHAPE_PROXYTYPE ? b : nullptr;
    const btCollisionObject* box = ta == BOX_SHAPE_PROXYTYPE ? a : tb == BOX_SHAPE_PROXYTYPE ? b : nullptr;
    if (sphere && box) {
      const btPersistentManifold* m = empty_manifold(pair, self.scratch_);
      if (m && sphere_far_from_box(*sphere, *box, m->getContactBreakingThreshold())) {
        ++self.skipped_;
        return;
      }
    }
  }
  btCollisionDispatcher::defaultNearCallback(pair, dispatcher, info);
}

}  // namespace gapflow::bullet3d

// Dispatcher3D: Bullet's collision dispatcher that skips the narrow phase of a
// sphere and a box that are certainly apart (private to sim3d; includes Bullet).
//
// The broad phase pairs bodies whose bounding boxes overlap. A long wall turned
// by 30° (the funnel) has a bounding box over most of the funnel, so nearly every
// sphere there is paired with it and Bullet runs GJK (btConvexConvexAlgorithm,
// there is no sphere-box algorithm in the default configuration) every step,
// although ~80 % of these calls find no contact (measured on the paper's
// discharge). GJK adds a contact point only when the sphere's centre is closer
// than radius + box margin + the manifold's breaking threshold to the box's core
// (the box shrunk by its margin), which is farther than the outer box: a centre
// more than 2 radii + that threshold from the outer box cannot give a point.
// When, in addition, the pair's manifold already exists and holds no point,
// Bullet's call would change nothing (no point to add, none to refresh; the
// algorithm keeps no state between calls), so skipping it leaves the run the same
// bit for bit. The first call of a pair (which creates the manifold) always runs,
// so manifolds are created and released in the same order as before.
#pragma once

#include <btBulletDynamicsCommon.h>

namespace gapflow::bullet3d {

class Dispatcher3D final : public btCollisionDispatcher {
 public:
  explicit Dispatcher3D(btCollisionConfiguration* config);
  void set_skip_far_pairs(bool skip) { skip_far_pairs_ = skip; }
  // Sphere-box narrow phases skipped since reset_counts() (for tests).
  long skipped_pairs() const { return skipped_; }
  void reset_counts() { skipped_ = 0; }

 private:
  static void near_callback(btBroadphasePair& pair, btCollisionDispatcher& dispatcher, const btDispatcherInfo& info);
  bool skip_far_pairs_ = true;
  btManifoldArray scratch_;
  long skipped_ = 0;
};

// True when the sphere's centre is more than 2 radii + `threshold` from the box
// (outer faces, btBoxShape's extents with margin), in the bodies' current poses.
bool sphere_far_from_box(const btCollisionObject& sphere, const btCollisionObject& box, btScalar threshold);

}  // namespace gapflow::bullet3d

// Solver3D: Bullet's sequential-impulse solver without the rolling-friction rows
// that can never act (private to sim3d; includes Bullet).
//
// For every contact whose combined rolling friction is > 0, Bullet adds three
// torque rows (btSequentialImpulseConstraintSolver::convertContact): one about the
// contact normal capped by the spinning friction, two about the tangents capped by
// the rolling friction. A row capped at zero (spinning friction 0, the default)
// is clamped to zero impulse in every iteration, so it only costs time; a rolling
// row capped at the session's floor (a rolling value Bullet needs only to build the
// spinning row) can apply at most 1e-12 m × the normal impulse, below float
// resolution. Solver3D removes both kinds after Bullet has built the rows, before
// the iterations; the rows that remain are solved in the same order as before.
#pragma once

#include <btBulletDynamicsCommon.h>

namespace gapflow::bullet3d {

class Solver3D final : public btSequentialImpulseConstraintSolver {
 public:
  // Rolling/spinning rows whose cap (engine length) is at most this are dropped;
  // 0 drops only the rows that are capped at zero.
  void set_negligible_cap(btScalar cap) { negligible_cap_ = cap; }
  // Rolling/spinning rows solved and dropped since reset_counts() (for tests).
  int rolling_rows() const { return kept_; }
  int dropped_rows() const { return dropped_; }
  void reset_counts() { kept_ = dropped_ = 0; }

 protected:
  void convertContacts(btPersistentManifold** manifolds, int count, const btContactSolverInfo& info) override;

 private:
  btScalar negligible_cap_ = 0;
  int kept_ = 0, dropped_ = 0;
};

}  // namespace gapflow::bullet3d

#include "sim3d/solver3d.hpp"

namespace gapflow::bullet3d {

// Rolling rows are not warm-started, not written back and not referred to by
// index (btSequentialImpulseConstraintSolver::solveSingleIteration walks the pool
// in order), so removing some leaves the others exactly as they were.
void Solver3D::convertContacts(btPersistentManifold** manifolds, int count, const btContactSolverInfo& info) {
  btSequentialImpulseConstraintSolver::convertContacts(manifolds, count, info);
  btConstraintArray& rows = m_tmpSolverContactRollingFrictionConstraintPool;
  int kept = 0;
  for (int i = 0; i < rows.size(); ++i) {
    if (rows[i].m_friction <= negligible_cap_) continue;
    if (kept != i) rows[kept] = rows[i];
    ++kept;
  }
  kept_ += kept;
  dropped_ += rows.size() - kept;
  rows.resizeNoInitialize(kept);
}

}  // namespace gapflow::bullet3d

// Materials of the 3D model: the scenario's pair values (friction by surface
// pair, restitution, rolling resistance from the board, spinning friction) in
// engine units, and Bullet's combiner hooks that look them up per contact.
#pragma once

#include "common/scenario.hpp"
#include "common/units.hpp"
#include "sim3d/session3d.hpp"


class btCollisionObject;

namespace gapflow::bullet3d {

// Marks (userIndex3) the bodies Session3D makes, so the combiner hooks leave any
// other Bullet user in the process on Bullet's own rules.
constexpr int kSessionBodyTag = 0x3D6A;

// Pair values in engine units, looked up by surface kind.
struct MaterialTable {
  double friction[3][3] = {};   // Coulomb, [kind a][kind b]
  double restitution = 0;       // every pair
  double rolling_resistance = 0;// dimensionless, board only; rolling friction = this * sphere radius
  double spinning = 0;          // engine length, every pair
  // Bullet only builds the spinning constraint when the rolling value is > 0;
  // this keeps it on when spinning friction is set but rolling resistance is 0
  // (Solver3D then drops the two rolling rows capped at this floor).
  double rolling_floor = 0;     // engine length
};

struct PairEngine {
  double friction, restitution, rolling, spinning;  // rolling, spinning: engine length
};

Surface3D kind_of(const btCollisionObject* o);
// The engine radius of a sphere body; 0 for any other shape.
double sphere_radius(const btCollisionObject* o);
// The values of one contact pair; ra, rb: engine radii (0 for a wall or the board).
PairEngine pair_values(const MaterialTable& t, Surface3D ka, double ra, Surface3D kb, double rb);
MaterialTable make_materials(const ParticlesDef& p, const EngineScaling& s);
// Installs the combiner hooks once per process; bodies tagged kSessionBodyTag
// carry their MaterialTable in their user pointer.
void install_combiner_hooks();

}  // namespace gapflow::bullet3d

// The front of a stopped flow, seen from the gap: which particles block it, and
// whether their arch leans on the obstruction.
//
// The front is the set of particles on the board that the gap sees: a free line
// of sight to some point of the gap line, with no other particle's disc and not
// the obstruction on the segment between. When the flow has stopped, the lowest
// arch is among them. Murray & Alonso-Marroquin (2016, Sec. IV, Fig. 2b) report
// that with an obstruction close to the gap "clogging appears between the
// obstruction and the walls": an arch with one foot on the obstruction and the
// other on a wall, instead of one from wall to wall. The gap monitor classifies
// each clog by the contact chains of its front (common/measurement.hpp).
#pragma once

#include "common/geometry.hpp"
#include "common/shaking.hpp"

#include <vector>

namespace gapflow {

struct BoardDisc {
  int id;         // particle index
  Vec2 centre;    // m, plane frame
  double radius;  // m
};

// Two spheres whose outlines are closer than this (in nominal diameters) touch:
// resting contacts overlap by about Box2D 2.4's linear slop, 0.005 units (0.005 d at
// the default engine_diameter of 1), and 0.02 d leaves room for that and round-off.
// Tighter than kBoundaryContactTolerance_d, so that two arches that merely come
// close are not read as one (tests/test_clog_front.cpp).
constexpr double kDiscContactTolerance_d = 0.02;
// A sphere touches a wall or the obstruction within this (in nominal diameters) plus
// that body's current shaking displacement: a shaken body moves at 20 Hz, faster
// than the spheres resting on it can follow.
constexpr double kBoundaryContactTolerance_d = 0.1;

// The ids of `discs` with a free line of sight to `eye` (plane frame, m); every
// disc in `discs` may hide another, and so does `obstruction`. Ids in the order of `discs`.
std::vector<int> visible_from(const ObstructionGeometry& obstruction, const std::vector<BoardDisc>& discs, Vec2 eye);

// The ids of `discs` that the gap sees: visible from at least one of the points
// spread along the gap line (y = 0, |x| < W/2) no more than d/2 apart. One point
// is not enough: an obstruction close to the gap hides everything from the gap
// centre while the arches beside it face the gap's ends. Ids in the order of `discs`.
std::vector<int> visible_from_gap(const CompiledScenario& sc, const ObstructionGeometry& obstruction,
                                  const std::vector<BoardDisc>& discs);

// The obstruction moved by a shaking displacement (m).
ObstructionGeometry displaced(const ObstructionGeometry& g, Vec2 offset);

// Whether a disc's outline is within `tolerance_m` of the obstruction's.
bool touches_obstruction(const ObstructionGeometry& obstruction, const BoardDisc& disc, double tolerance_m);

// Whether the arch of a stopped flow leans on the obstruction, judged from the
// front (the discs the gap sees, with the walls and obstruction where the shaking
// schedule has them at that moment). Discs touch within kDiscContactTolerance_d,
// walls and obstruction within kBoundaryContactTolerance_d plus their current
// shaking displacement. True when a chain of touching front
// discs links the obstruction to a wall (bottleneck or retaining) and no chain
// links the two walls without it: an arch from wall to wall that merely rests on
// the obstruction is an arch across the gap, not one between obstruction and walls.
bool front_leans_on_obstruction(const CompiledScenario& sc, const std::vector<BoardDisc>& board,
                                const ShakeOffsets& offsets);

}  // namespace gapflow

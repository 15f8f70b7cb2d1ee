// The front of a stopped flow, seen from the gap: which particles block it, and
// whether they lean on the obstruction.
//
// The front is the set of particles on the board that the gap sees: a free line
// of sight to some point of the gap line, with no other particle's disc and not
// the obstruction on the segment between. When the flow has stopped they are the
// lowest arch (its spheres face the gap) and whatever the gap sees past its
// ends. Murray & Alonso-Marroquin (2016, Sec. IV, Fig. 2b) report that with an
// obstruction close to the gap "clogging appears between the obstruction and the
// walls": an arch with one foot on the obstruction, i.e. a front particle that
// touches it. The gap monitor classifies each clog by it (common/measurement.hpp);
// the local-perturbation protocol lifts what the gap centre sees near the gap
// (common/protocols.hpp).
#pragma once

#include "common/geometry.hpp"

#include <vector>

namespace gapflow {

struct BoardDisc {
  int id;         // particle index
  Vec2 centre;    // m, plane frame
  double radius;  // m
};

// The ids of `discs` with a free line of sight to `viewpoint` (plane frame, m);
// every disc in `discs` may hide another, and so does the obstruction (rest
// position). Ids are returned in the order of `discs`.
std::vector<int> visible_from(const ObstructionGeometry& obstruction, const std::vector<BoardDisc>& discs, Vec2 viewpoint);

// The ids of `discs` that the gap sees: visible from at least one of the points
// spread along the gap line (y = 0, |x| < W/2) no more than d/2 apart. One point
// is not enough: an obstruction close to the gap hides everything from the gap
// centre while the arches beside it face the gap's ends. Ids in the order of `discs`.
std::vector<int> visible_from_gap(const CompiledScenario& sc, const std::vector<BoardDisc>& discs);

// Whether a disc touches the obstruction: the gap between their outlines is at
// most `tolerance_m` (contacts overlap or part by a little, and a shaken
// obstruction is up to its amplitude off its rest position).
bool touches_obstruction(const ObstructionGeometry& obstruction, const BoardDisc& disc, double tolerance_m);

// The tolerance for touches_obstruction in a scenario: 0.1 d plus the
// obstruction's shaking amplitude when it is shaken.
double obstruction_contact_tolerance(const CompiledScenario& sc);

}  // namespace gapflow

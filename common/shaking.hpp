// Shaking schedules: where the kinematic walls and obstruction must be at time t.
#pragma once

#include "common/scenario.hpp"

namespace gapflow {

// Displacements from the rest position, lab metres, plane frame.
struct ShakeOffsets {
  Vec2 left_wall;
  Vec2 right_wall;
  Vec2 obstruction;
};

// Displacement (m) of one schedule at time t (s after release). mirrored: x component negated.
Vec2 shake_displacement(const ShakeDef& shake, double t, bool mirrored = false);

ShakeOffsets shake_offsets(const ShakingDef& shaking, double t);

}  // namespace gapflow

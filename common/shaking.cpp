#include "common/shaking.hpp"

#include "common/units.hpp"

#include <cmath>

namespace gapflow {

Vec2 shake_displacement(const ShakeDef& shake, double t, bool mirrored) {
  if (!shake.enabled || t < shake.start_s) return {};
  const double tau = std::fmod(t - shake.start_s, shake.period_s);  // s into the current shake
  if (tau >= shake.decay_s) return {};
  // Starts and ends at zero displacement, so the kinematic bodies never jump.
  const double envelope = mm_to_m(shake.amplitude_mm) * (1.0 - tau / shake.decay_s);
  const double s = envelope * std::sin(2.0 * kPi * shake.frequency_hz * tau);
  const double a = deg_to_rad(shake.direction_deg);
  return {(mirrored ? -1.0 : 1.0) * s * std::cos(a), s * std::sin(a)};
}

ShakeOffsets shake_offsets(const ShakingDef& shaking, double t) {
  ShakeOffsets o;
  o.right_wall = shake_displacement(shaking.walls, t, false);
  o.left_wall = shake_displacement(shaking.walls, t, shaking.walls.mirror);
  o.obstruction = shake_displacement(shaking.obstruction, t, false);
  return o;
}

}  // namespace gapflow

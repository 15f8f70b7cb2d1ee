#include "calibrate/effect_catalogue.hpp"

#include "common/scenario_loader.hpp"

#include <toml++/toml.h>

namespace gapflow {

const std::vector<EffectDef>& effect_catalogue() {
  // Ranges: what a real board and real beads could plausibly have (rolling
  // resistance: hard balls on smooth steel 1e-5 - 1e-3, a rough or coated board
  // more; the top of the range is a felt-like board). Steps: about half the
  // range, so that a finite difference at 4-8 replicates beats the noise and a
  // size anywhere in the range is at most ~2 steps from the neutral value.
  static const std::vector<EffectDef> catalogue{
      {"rolling_resistance", "particles.rolling_resistance", "",
       "resistance from the board, a force mu_r m g cos(theta) against the velocity", 0.0, 0.02, 0.01,
       {.acts_through_board = true}},
      {"spinning_friction", "particles.spinning_friction_mm", "mm",
       "torsional friction about the board normal, torque s m g cos(theta)", 0.0, 1.0, 0.5,
       {.acts_through_board = true}},
      // Step toward smoother walls: above the particle friction (0.24) the flow stops feeling the
      // walls' (the layer at a wall slips on its neighbours instead), below it J rises steeply
      // (results/wall-friction-response: J_mid at W/d 4.5 +9 % from 0.24 to 0.05, -3 % from 0.24
      // to 0.8; at W/d 3.5 +21 % and -2 %, noisier). A step up measured nearly nothing, and twins
      // planted there were null twins. The range's upper end stays (a rough wall is plausible) but
      // lies 3.7 steps from neutral, beyond the header's rule: twins are planted on the step's side.
      {"wall_friction", "particles.friction_wall", "",
       "Coulomb friction against walls and obstruction different from particle-particle friction", 0.05, 0.8,
       -0.15, {}},
      {"size_scatter", "particles.size_scatter", "", "relative half-width of the particle size distribution",
       0.0, 0.2, 0.1, {}},
      {"restitution", "particles.restitution", "", "pair coefficient of restitution", 0.0, 0.95, -0.4, {}},
      {"lateral_tilt", "plane.lateral_tilt_deg", "deg",
       "the board rolled about its fall line: gravity g cos(theta) sin(phi) across the channel", 0.0, 6.0, 4.0,
       {.acts_through_board = true}},
      {"gap_offset", "bottleneck.gap_offset_mm", "mm",
       "the wall tips stand further apart than drawn (effective gap W + delta)", -3.0, 3.0, 1.5, {}},
      {"linear_drag", "particles.drag_per_s", "1/s",
       "viscous drag -gamma m v on each particle (air, a film on the board)", 0.0, 6.0, 2.0, {},
       /*speed_law=*/true},
      {"corner_rounding", "obstruction.corner_radius_mm", "mm",
       "the obstruction's corners rounded to radius r (faces stay in place)", 0.0, 3.0, 2.0,
       {.needs_polygon_obstruction = true}},
      // Derived size 1 (README, "The 2D model"); step 0.5 = half the range: on the blind design's
      // set-up (150 spheres, W/d 4.5, 8 deg, 6 replicates) J_mid fell 11 % at 0.5 (92.1 +- 4.9 -> 81.7
      // +- 5.3 /s) and 14 % at 1. 2D only: the 3D model has this friction natively.
      {"rolling_contact", "model.box2d.rolling_contact", "",
       "vertical sliding friction at contacts of rolling spheres (a pushing pair rubs at 2v), as a fraction "
       "of the derived force",
       0.0, 1.0, 0.5, {.in_3d = false, .acts_through_board = true, .needs_rolling = true}},
  };
  return catalogue;
}

const EffectDef* find_effect(const std::string& name) {
  for (const EffectDef& e : effect_catalogue())
    if (e.name == name) return &e;
  return nullptr;
}

bool effect_applies(const EffectDef& effect, ModelKind model, const DataFile& data) {
  if (model == ModelKind::box2d ? !effect.scope.in_2d : !effect.scope.in_3d) return false;
  for (const FreeParameter& f : data.free)
    if (f.key == effect.key) return false;
  bool polygon = false, board = false, rolling = false;
  for (std::size_t i = 0; i < data.points.size(); ++i) {
    const ScenarioDef def = data.point_scenario(i).def;
    polygon = polygon || def.obstruction.shape == ObstructionShape::triangle ||
              def.obstruction.shape == ObstructionShape::polygon;
    board = board || def.plane.incline_deg < 90;
    rolling = rolling || def.model.box2d.rolling.enabled;
  }
  if (effect.scope.needs_polygon_obstruction && !polygon) return false;
  if (effect.scope.acts_through_board && !board) return false;
  if (effect.scope.needs_rolling && model == ModelKind::box2d && !rolling) return false;
  return true;
}

bool key_applies_to(const std::string& key, const ScenarioDef& point) {
  if (key != "obstruction.corner_radius_mm") return true;
  return point.obstruction.shape == ObstructionShape::triangle || point.obstruction.shape == ObstructionShape::polygon;
}

double template_value(const std::string& key, const DataFile& data) {
  // The canonical TOML of the resolved template holds every key that is set; keys
  // written only when set (the effects' switches) are absent at their default, 0.
  const toml::table doc = toml::parse(canonical_toml(data.point_scenario(0).def));
  return toml::at_path(doc, key).value<double>().value_or(0.0);
}

double neutral_value(const EffectDef& effect, const DataFile& data) { return template_value(effect.key, data); }

}  // namespace gapflow

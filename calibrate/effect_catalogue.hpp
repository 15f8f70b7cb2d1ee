// The effect catalogue: the physical effects the calibration loop can look for
// when a model misses measured data. One list (effect_catalogue()); adding an
// effect is adding an entry. Every entry is a real scenario key of the models it
// applies to, tested on its own (tests/test_sim2d.cpp, tests/test_sim3d.cpp,
// tests/test_effects.cpp), with a plausible size range and a physical step: the
// finite difference that measures the effect's signature must be large enough to
// beat the simulation noise at the replicate counts a calibration uses.
#pragma once

#include "calibrate/data_file.hpp"
#include "models/registry.hpp"

#include <string>
#include <vector>

namespace gapflow {

// Where an effect can act (written with designated initializers in the catalogue).
struct EffectScope {
  bool in_2d = true;                       // the 2D model has it
  bool in_3d = true;                       // the 3D model has it
  bool needs_polygon_obstruction = false;  // only visible when some design point has a triangle/polygon obstruction
  bool acts_through_board = false;         // its force is m g cos(theta) x something: nothing in a vertical silo
  bool needs_rolling = false;              // the 2D model's rolling spheres carry it (refused with rolling off)
};

struct EffectDef {
  std::string name;       // short identifier used in reports ("rolling_resistance")
  std::string key;        // scenario key that switches it on ("particles.rolling_resistance")
  std::string unit;       // unit of the key's value ("", "mm", "deg", "1/s")
  std::string physics;    // one line: what it is
  double lo = 0, hi = 0;  // plausible range of the key's value (lab units)
  double step = 0;        // physical step for the signature (key units; sign = direction)
  EffectScope scope;      // where it can act
  // A force that is a power of the speed (a drag): the loop reads it with one law (the catalogue's,
  // linear), and the form check asks whether the design could tell that law from another one
  // (form_check.hpp, "the law in the speed").
  bool speed_law = false;
};

// The catalogue, in a fixed order.
const std::vector<EffectDef>& effect_catalogue();
// nullptr when no effect has this name.
const EffectDef* find_effect(const std::string& name);

// Whether `effect` can show in this model and design (a corner radius needs a
// polygonal obstruction somewhere; a board's friction or tilt needs a point whose
// board is not vertical; the rolling contact needs rolling spheres; a free
// parameter of the data file is no effect).
bool effect_applies(const EffectDef& effect, ModelKind model, const DataFile& data);

// Whether setting `key` means anything at a point with this scenario: a corner
// radius only where the obstruction has corners (elsewhere the override is left
// out: the effect is zero there, and the loader rightly refuses the key).
bool key_applies_to(const std::string& key, const ScenarioDef& point);

// The value the data file's template (with its fixed overrides) gives the effect's
// key: the model "without the effect".
double neutral_value(const EffectDef& effect, const DataFile& data);
// The same for any numeric scenario key (0 where the template leaves it unset).
double template_value(const std::string& key, const DataFile& data);

}  // namespace gapflow

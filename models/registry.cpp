#include "models/registry.hpp"

#include "sim2d/model2d.hpp"
#include "sim3d/model3d.hpp"
#include "common/scenario_loader.hpp"
#include "common/units.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace gapflow {

ModelKind parse_model_kind(const std::string& name) {
  if (name == "2d") return ModelKind::box2d;
  if (name == "3d") return ModelKind::bullet;
  throw std::invalid_argument("model '" + name + "' is not one of: 2d, 3d");
}

const char* to_string(ModelKind kind) { return kind == ModelKind::box2d ? "2d" : "3d"; }

namespace {

// The 2D model's rolling reduction holds only while the board's friction can
// supply the torque: a sphere of inertia factor k rolls without slipping while
// mu_base >= k/(1+k) tan(theta) (2/7 tan(theta) for a solid sphere: up to 40 deg
// at mu_base 0.24). Beyond it spheres slide, and at 90 deg (a vertical silo)
// nothing presses them on the board: the scenario must say so.
void check_rolling_holds(const ScenarioDef& d) {
  const Box2DRollingDef& r = d.model.box2d.rolling;
  if (!r.enabled) return;
  const double k = r.inertia_factor, mu = d.particles.friction_base;
  const double limit_deg = rad_to_deg(std::atan(mu * (1 + k) / k));
  if (d.plane.incline_deg <= limit_deg) return;
  throw ScenarioInvalid("plane.incline_deg", fmt::format("{:g}", d.plane.incline_deg),
                        fmt::format("at most {:.1f} deg while model.box2d.rolling.enabled = true: spheres roll without "
                                    "slipping only while tan(theta) <= particles.friction_base (1+k)/k = {:.3g} (k = "
                                    "{:g}); steeper, set model.box2d.rolling.enabled = false (a vertical silo)",
                                    limit_deg, mu * (1 + k) / k, k));
}

}  // namespace

// What a model cannot run, said before it runs. On a 3D board steeper than 60 deg
// spheres are barely pressed onto it, and at 90 deg nothing keeps them there: a
// quasi-2D cell needs its cover plate (plane.cover_gap_mm).
void check_model_supports(const CompiledScenario& scenario, ModelKind kind) {
  if (kind == ModelKind::box2d) check_rolling_holds(scenario.def);
  if (kind != ModelKind::bullet) return;
  const ScenarioDef& d = scenario.def;
  if (d.plane.incline_deg > 60 && d.plane.cover_gap_mm == 0)
    throw ScenarioInvalid("plane.incline_deg", fmt::format("{:g}", d.plane.incline_deg),
                          "at most 60 deg for the 3D model without a cover plate (plane.cover_gap_mm > 0 holds the "
                          "spheres in a monolayer on a steeper board); the 2D model takes up to 90");
  if (d.plane.cover_gap_mm == 0) return;
  // The plate must clear every sphere and close the cell below the walls' top.
  double largest_mm = 0;
  for (const auto& p : scenario.particles) largest_mm = std::max(largest_mm, p.diameter * 1e3);
  const double walls_mm = d.model.bullet.wall_height_d * d.particles.diameter_mm;
  if (d.plane.cover_gap_mm <= largest_mm || d.plane.cover_gap_mm > walls_mm)
    throw ScenarioInvalid("plane.cover_gap_mm", fmt::format("{:g}", d.plane.cover_gap_mm),
                          fmt::format("must exceed the largest sphere ({:.4g} mm) and not exceed the walls' height "
                                      "(model.bullet.wall_height_d x d = {:.4g} mm)",
                                      largest_mm, walls_mm));
}

std::unique_ptr<EngineSession> make_session(const CompiledScenario& scenario, ModelKind kind) {
  check_model_supports(scenario, kind);
  return kind == ModelKind::box2d ? make_session_2d(scenario) : make_session_3d(scenario);
}

RunRecord run_model(const CompiledScenario& scenario, ModelKind kind, const StepObserver* observer,
                    const std::atomic<bool>* cancel) {
  auto session = make_session(scenario, kind);
  return run_simulation(scenario, *session, observer, cancel);
}

}  // namespace gapflow

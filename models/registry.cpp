#include "models/registry.hpp"

#include "sim2d/model2d.hpp"
#include "sim3d/model3d.hpp"
#include "common/scenario_loader.hpp"

#include <fmt/format.h>

#include <stdexcept>

namespace gapflow {

ModelKind parse_model_kind(const std::string& name) {
  if (name == "2d") return ModelKind::box2d;
  if (name == "3d") return ModelKind::bullet;
  throw std::invalid_argument("model '" + name + "' is not one of: 2d, 3d");
}

const char* to_string(ModelKind kind) { return kind == ModelKind::box2d ? "2d" : "3d"; }

// What a model cannot run, said before it runs. The 3D board has no cover plate
// yet: on a board steeper than 60 deg spheres are barely pressed onto it, and at
// 90 deg nothing keeps them there (a quasi-2D cell needs the plate).
void check_model_supports(const CompiledScenario& scenario, ModelKind kind) {
  if (kind == ModelKind::bullet && scenario.def.plane.incline_deg > 60)
    throw ScenarioInvalid("plane.incline_deg", fmt::format("{:g}", scenario.def.plane.incline_deg),
                          "at most 60 deg for the 3D model (it has no cover plate to hold spheres on a steeper board); "
                          "the 2D model takes up to 90");
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

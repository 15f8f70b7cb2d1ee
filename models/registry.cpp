#include "models/registry.hpp"

#include "sim2d/model2d.hpp"
#include "sim3d/model3d.hpp"

#include <stdexcept>

namespace gapflow {

ModelKind parse_model_kind(const std::string& name) {
  if (name == "2d") return ModelKind::box2d;
  if (name == "3d") return ModelKind::bullet;
  throw std::invalid_argument("model '" + name + "' is not one of: 2d, 3d");
}

const char* to_string(ModelKind kind) { return kind == ModelKind::box2d ? "2d" : "3d"; }

std::unique_ptr<EngineSession> make_session(const CompiledScenario& scenario, ModelKind kind) {
  return kind == ModelKind::box2d ? make_session_2d(scenario) : make_session_3d(scenario);
}

RunRecord run_model(const CompiledScenario& scenario, ModelKind kind, const StepObserver* observer,
                    const std::atomic<bool>* cancel) {
  auto session = make_session(scenario, kind);
  return run_simulation(scenario, *session, observer, cancel);
}

}  // namespace gapflow

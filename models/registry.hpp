// Model registry: the one place that knows every engine (models/ sits between the
// engines, sim2d/ and sim3d/, and everything that runs them: studies, calibration, app).
#pragma once

#include "common/simulation.hpp"

#include <memory>
#include <string>

namespace gapflow {

enum class ModelKind { box2d, bullet };
// "2d" | "3d"; throws std::invalid_argument otherwise.
ModelKind parse_model_kind(const std::string& name);
const char* to_string(ModelKind kind);  // "2d" | "3d"

// Throws ScenarioInvalid when the model cannot run the scenario: the 2D rolling reduction where
// spheres would slip, the 3D model above 60 deg.
void check_model_supports(const CompiledScenario& scenario, ModelKind kind);
std::unique_ptr<EngineSession> make_session(const CompiledScenario& scenario, ModelKind kind);

// Build the session for `kind` and run it.
RunRecord run_model(const CompiledScenario& scenario, ModelKind kind, const StepObserver* observer = nullptr,
                    const std::atomic<bool>* cancel = nullptr);

}  // namespace gapflow

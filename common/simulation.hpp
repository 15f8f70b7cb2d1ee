// The run driver shared by both models: settle, release, step, measure, stop.
#pragma once

#include "common/engine_session.hpp"
#include "common/measurement.hpp"
#include "common/run_record.hpp"

#include <functional>
#include <string>

namespace gapflow {

// Called after every step after release (tests, live views). t in s after release.
struct StepObserver {
  std::function<void(double t, const EngineSession&, const GapMonitor&)> after_step;
};

// One complete run. Deterministic for a given scenario (seed inside it).
RunRecord run_simulation(const CompiledScenario& scenario, EngineSession& session,
                         const StepObserver* observer = nullptr);

}  // namespace gapflow

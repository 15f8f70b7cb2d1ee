// The run driver shared by both models: settle, release, step, measure, stop.
#pragma once

#include "common/engine_session.hpp"
#include "common/measurement.hpp"
#include "common/run_record.hpp"

#include <atomic>
#include <functional>
#include <stdexcept>
#include <string>

namespace gapflow {

// Called after every step after release (tests, live views). t in s after release.
struct StepObserver {
  std::function<void(double t, const EngineSession&, const GapMonitor&)> after_step;
};

// Thrown by run_simulation when its cancel flag is raised (Ctrl-C in a study).
struct RunCancelled : std::runtime_error {
  RunCancelled() : std::runtime_error("run cancelled") {}
};

// One complete run. Deterministic for a given scenario (seed inside it).
// `cancel`, when given and set (by another thread or a signal handler), stops
// the run between steps with RunCancelled: a cancelled run leaves no record.
RunRecord run_simulation(const CompiledScenario& scenario, EngineSession& session,
                         const StepObserver* observer = nullptr, const std::atomic<bool>* cancel = nullptr);

}  // namespace gapflow

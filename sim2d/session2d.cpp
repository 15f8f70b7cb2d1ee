// Session2D: one run of the Box2D model. The step is a list of named stages.
#include "sim2d/session2d.hpp"

#include <algorithm>

namespace gapflow {

std::unique_ptr<EngineSession> make_session_2d(const CompiledScenario& scenario) {
  return std::make_unique<Session2D>(scenario);
}

}  // namespace gapflow

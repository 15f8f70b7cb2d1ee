// The reduced 2D model (Box2D 2.4): the board seen from above.
#pragma once

#include "common/engine_session.hpp"

#include <memory>

namespace gapflow {

std::unique_ptr<EngineSession> make_session_2d(const CompiledScenario& scenario);

}  // namespace gapflow

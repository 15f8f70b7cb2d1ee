// The full 3D model (Bullet 3): spheres rolling on the tilted board.
#pragma once

#include "common/engine_session.hpp"

#include <memory>

namespace gapflow {

std::unique_ptr<EngineSession> make_session_3d(const CompiledScenario& scenario);

}  // namespace gapflow

// One picture's worth of a run: what the views (snapshot, movie, VTK, live view)
// draw, captured from an EngineSession and a GapMonitor between two steps.
// Capturing reads every particle once; the writers call it only for the frames
// they emit, so a run without outputs pays nothing.
#pragma once

#include "common/clog_front.hpp"
#include "common/engine_session.hpp"
#include "common/measurement.hpp"

#include <string>
#include <vector>

namespace gapflow {

// What a particle is doing, as the gap monitor sees it.
enum class ParticleState : int {
  flowing = 0,  // on the board (inside), flow not stopped
  arch = 1,     // on the board while the flow is stopped (a clog): in the front the gap sees
  passed = 2,   // crossed the gap line, still simulated below it
  stuck = 3     // on the board while the flow is stopped, behind the front
};
const char* to_string(ParticleState s);

struct ParticleView {
  int id = 0;                 // particle index
  double x = 0, y = 0, z = 0; // m, centre, plane frame (z above the board)
  double radius = 0;          // m, true radius
  double vx = 0, vy = 0, vz = 0;  // m/s
  double wx = 0, wy = 0, wz = 0;  // rad/s
  ParticleState state = ParticleState::flowing;
  double speed() const;       // m/s, |v|
};

struct FrameState {
  std::string model;          // "2d" or "3d"
  double t = 0;               // s after release
  int passed = 0;             // crossings so far
  int clogs = 0;              // clogs detected so far
  bool clogged = false;       // no crossing for clog_timeout_s with particles on the board
  bool arch_on_obstruction = false;  // when clogged: the clog locator's verdict (common/clog_front.hpp)
  ShakeOffsets offsets;       // m, walls and obstruction displaced by the shaking at t
  std::vector<ParticleView> particles;
  double j_so_far() const;    // 1/s, passed / t (0 before the first step)
};

// Read the session and monitor after a step that ended at t. `clogs` is the
// caller's count of clogs detected so far. `scratch` avoids an allocation per frame.
FrameState capture_frame(const CompiledScenario& sc, const EngineSession& session, const GapMonitor& monitor,
                         double t, int clogs, std::vector<ParticleMotion>& scratch);

// Whether the flow is stopped at t by the monitor's clog rule (no crossing for
// clog_timeout_s while particles are on the board).
bool flow_stopped(const CompiledScenario& sc, const GapMonitor& monitor, double t);

// Mark the particles of a stopped flow: the front the gap sees (clog_front.hpp) as
// `arch`, the rest on the board as `stuck`; sets arch_on_obstruction.
void mark_clog_front(const CompiledScenario& sc, FrameState& frame);

}  // namespace gapflow

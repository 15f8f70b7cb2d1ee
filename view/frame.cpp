#include "view/frame.hpp"

#include "common/shaking.hpp"

#include <cmath>

namespace gapflow {

const char* to_string(ParticleState s) {
  switch (s) {
    case ParticleState::flowing: return "flowing";
    case ParticleState::arch: return "arch";
    case ParticleState::passed: return "passed";
    case ParticleState::stuck: return "stuck";
  }
  return "?";
}

double ParticleView::speed() const { return std::sqrt(vx * vx + vy * vy + vz * vz); }

double FrameState::j_so_far() const { return t > 0 ? passed / t : 0.0; }

bool flow_stopped(const CompiledScenario& sc, const GapMonitor& monitor, double t) {
  return monitor.inside() > 0 && t - monitor.last_crossing_time() >= sc.def.run.clog_timeout_s;
}

FrameState capture_frame(const CompiledScenario& sc, const EngineSession& session, const GapMonitor& monitor,
                         double t, int clogs, std::vector<ParticleMotion>& scratch) {
  FrameState f;
  f.model = session.model_name();
  f.t = t;
  f.passed = monitor.passed();
  f.clogs = clogs;
  f.clogged = flow_stopped(sc, monitor, t);
  f.offsets = shake_offsets(sc.def.shaking, t);
  session.particle_motions(scratch);
  f.particles.reserve(scratch.size());
  for (const ParticleMotion& m : scratch) {
    ParticleView p;
    p.id = m.id;
    p.x = m.position.x;
    p.y = m.position.y;
    p.z = m.z;
    p.radius = sc.particles[static_cast<size_t>(m.id)].diameter / 2;
    p.vx = m.vx, p.vy = m.vy, p.vz = m.vz;
    p.wx = m.wx, p.wy = m.wy, p.wz = m.wz;
    p.state = monitor.is_inside(m.id) ? ParticleState::flowing : ParticleState::passed;
    f.particles.push_back(p);
  }
  if (f.clogged) mark_clog_front(sc, f);
  return f;
}

void mark_clog_front(const CompiledScenario& sc, FrameState& frame) {
  std::vector<BoardDisc> board;
  for (const ParticleView& p : frame.particles)
    if (p.state != ParticleState::passed) board.push_back({p.id, {p.x, p.y}, p.radius});
  const ObstructionGeometry obstruction = displaced(sc.obstruction, frame.offsets.obstruction);
  const std::vector<int> front = visible_from_gap(sc, obstruction, board);
  std::vector<char> in_front(sc.particles.size(), 0);
  for (int id : front) in_front[static_cast<size_t>(id)] = 1;
  for (ParticleView& p : frame.particles)
    if (p.state != ParticleState::passed)
      p.state = in_front[static_cast<size_t>(p.id)] ? ParticleState::arch : ParticleState::stuck;
  frame.clogged = true;
  frame.arch_on_obstruction =
      sc.obstruction.shape != ObstructionShape::none && front_leans_on_obstruction(sc, board, frame.offsets);
}

}  // namespace gapflow

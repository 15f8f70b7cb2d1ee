// The run driver, written as a list of named stages:
//   settle against the closed barrier -> come to rest -> open the barrier ->
//   loop { move shakers -> step physics -> measure -> retire -> stop? } -> record.
#include "common/simulation.hpp"

#include "common/protocols.hpp"

#include <chrono>
#include <cmath>

namespace gapflow {

namespace {

void settle(const CompiledScenario& sc, EngineSession& session) {
  session.set_barrier(true);
  session.set_shake_targets({});
  const auto steps = static_cast<long>(std::llround(sc.def.release.settle_s / session.time_step()));
  for (long i = 0; i < steps; ++i) session.step();
  session.zero_velocities();  // "released from rest"
  session.set_barrier(false);
}

void fill_identity(const CompiledScenario& sc, const EngineSession& session, RunRecord& r) {
  r.model = session.model_name();
  r.scenario_name = sc.def.name;
  r.scenario_hash = sc.scenario_hash;
  r.base_seed = sc.def.run.seed;
  r.replicate = sc.def.run.replicate;
  r.run_seed = sc.run_seed;
  r.time_step_s = session.time_step();
  r.diameter_m = sc.nominal_diameter;
  r.gap_m = sc.declared_gap;  // the declared W, also when the walls stand elsewhere (bottleneck.gap_offset_mm)
  r.distance_m = sc.def.obstruction.shape == ObstructionShape::none ? 0.0 : sc.def.obstruction.distance_mm * 1e-3;
  r.incline_rad = sc.incline;
}

}  // namespace

RunRecord run_simulation(const CompiledScenario& sc, EngineSession& session, const StepObserver* observer,
                         const std::atomic<bool>* cancel) {
  const auto wall_start = std::chrono::steady_clock::now();
  settle(sc, session);

  GapMonitor monitor(sc);
  ClogProtocol protocol(sc);
  const double dt = session.time_step();
  std::vector<ActiveParticle> active;
  std::vector<int> retiring, passed_below;
  double t = 0;
  EndReason reason = EndReason::time_limit;
  for (long step = 1;; ++step) {
    if (cancel && cancel->load(std::memory_order_relaxed)) throw RunCancelled();
    const double t_next = step * dt;  // no accumulated round-off
    session.set_shake_targets(shake_offsets(sc.def.shaking, t_next));
    session.step();
    t = t_next;

    session.active_particles(active);
    retiring.clear();
    passed_below.clear();
    for (const ActiveParticle& p : active) {
      const ParticleFate fate = monitor.observe(p.id, p.position, t);
      if (fate == ParticleFate::escaped) retiring.push_back(p.id);
      if (fate == ParticleFate::passed_retire)
        (protocol.reinjects_passed() ? passed_below : retiring).push_back(p.id);
    }
    monitor.end_step(t);
    if (!retiring.empty()) session.retire(retiring);
    protocol.apply(t, session, monitor, active, passed_below);
    if (observer && observer->after_step) observer->after_step(t, session, monitor);

    const StopDecision stop = should_stop(sc.def.run, monitor, t);
    if (stop.stop) {
      reason = stop.reason;
      break;
    }
  }

  RunRecord record;
  fill_identity(sc, session, record);
  monitor.finish(t, reason, record);
  record.perturbations = protocol.perturbations();
  record.wall_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count();
  return record;
}

}  // namespace gapflow

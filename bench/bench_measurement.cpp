// The cost of measurement as a fraction of stepping.
//
// The paper's medium scenario, released at once and advanced step by step
// exactly as common/simulation.cpp's loop does: move shakers, step, read the
// positions, GapMonitor::observe every particle, end_step, retire. The thread's
// CPU clock (not the wall clock: the machine may be shared) splits each iteration into "step" (shakers + step()) and "measure" (position
// read-out, observe over all particles with crossing detection, end_step); the
// record building (GapMonitor::finish: sort, avalanches, clogs, J) is added to
// "measure" at the end. Retirement is engine work and is in neither.
// If the driver's loop changes, change this mirror too.
#include "bench/bench_support.hpp"
#include "common/measurement.hpp"

#include <benchmark/benchmark.h>


namespace gapflow::bench {
namespace {

void BM_Measurement(benchmark::State& state, ModelKind kind, double warmup_s) {
  FlowingHopper hopper(source_path(kPaperMedium), {}, kind);
  EngineSession& session = hopper.session();
  const CompiledScenario& sc = hopper.scenario();
  GapMonitor monitor(sc);  // release is now: the monitor sees the whole flow, warm-up included
  std::vector<ActiveParticle> active;
  std::vector<int> retiring;
  double t_step = 0, t_measure = 0, observations = 0;

  auto one_step = [&](bool timed) {
    const double t0 = thread_cpu_seconds();
    hopper.advance(1);
    const double t1 = thread_cpu_seconds();
    const double t = hopper.time();
    session.active_particles(active);
    retiring.clear();
    for (const ActiveParticle& p : active) {
      const ParticleFate fate = monitor.observe(p.id, p.position, t);
      if (fate == ParticleFate::escaped || fate == ParticleFate::passed_retire) retiring.push_back(p.id);
    }
    monitor.end_step(t);
    const double t2 = thread_cpu_seconds();
    if (!retiring.empty()) session.retire(retiring);
    if (timed) {
      t_step += t1 - t0;
      t_measure += t2 - t1;
      observations += static_cast<double>(active.size());
    }
  };

  for (long i = hopper.steps_for(warmup_s); i > 0; --i) one_step(false);
  for (auto _ : state) one_step(true);

  RunRecord record;
  const double f0 = thread_cpu_seconds();
  monitor.finish(hopper.time(), EndReason::time_limit, record);
  t_measure += thread_cpu_seconds() - f0;

  state.counters["measure_fraction"] = t_measure / t_step;
  state.counters["measure_ns_per_particle"] = 1e9 * t_measure / observations;
  state.counters["step_ns_per_particle"] = 1e9 * t_step / observations;
  state.counters["check_passed"] = record.passed;
  state.counters["check_escaped"] = record.escaped;
  state.counters["check_hash"] = crossings_hash(record);
}

// 1 s of flow in 2D (1000 steps of 1 ms), 0.2 s in 3D (200 steps of 1 ms), after a short warm-up.
BENCHMARK_CAPTURE(BM_Measurement, paper_medium_2d, ModelKind::box2d, 0.15)
    ->Name("Measurement2D/paper_medium")
    ->Iterations(1000)
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_Measurement, paper_medium_3d, ModelKind::bullet, 0.1)
    ->Name("Measurement3D/paper_medium")
    ->Iterations(200)
    ->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace gapflow::bench

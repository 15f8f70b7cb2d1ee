// Step cost against particle count, in a flowing hopper.
//
// Scene: scenarios/paper/no_obstruction_medium.toml with particles.count = N
// and a board widened/lengthened to hold them (bench_support.hpp board_for);
// the label of each benchmark is the exact --set list. The hopper is opened at
// once, advanced kWarmup seconds (the lattice packing collapses and the outflow
// at the gap starts), then a fixed number of steps is timed. The step count is
// fixed (->Iterations) rather than chosen by Google Benchmark so that every
// repetition and every machine ends in the same state: the state hash counter
// then detects a change of the physics.
#include "bench/bench_support.hpp"

#include <benchmark/benchmark.h>

#include <cmath>

namespace gapflow::bench {
namespace {

// Warm-up before timing, s (lab). The packing starts with lattice_gap between
// sites; its collapse runs up the pile and reaches the top row of the
// 20000-particle board after about 0.3 s (until then the top rows fall freely
// and cost less than a resting pile).
constexpr double kWarmup2D = 0.3;
constexpr double kTimed2D = 0.25;  // s (lab) timed: 250 steps of 1 ms
constexpr double kWarmup3D = 0.3;
constexpr double kTimed3D = 0.2;   // s (lab) timed: 200 steps of the default 1 ms

void run_step_benchmark(benchmark::State& state, ModelKind kind, double warmup_s, double timed_s) {
  const int count = static_cast<int>(state.range(0));
  const std::vector<std::string> overrides = board_for(source_path(kPaperMedium), count);
  FlowingHopper hopper(source_path(kPaperMedium), overrides, kind);
  if (std::abs(hopper.session().time_step() * static_cast<double>(state.max_iterations) - timed_s) > 1e-9) {
    state.SkipWithError("the scenario's time step changed: update kSteps2D/kSteps3D");
    return;
  }
  hopper.advance(hopper.steps_for(warmup_s));

  const auto particles = static_cast<double>(hopper.positions().size());
  const double cpu0 = thread_cpu_seconds();
  for (auto _ : state) hopper.advance(1);
  const double cpu = thread_cpu_seconds() - cpu0;

  const std::vector<ActiveParticle> end = hopper.positions();
  const double particle_steps = particles * static_cast<double>(state.iterations());
  // Per CPU second (the thread's, as Google Benchmark's CPU column): the cost
  // of the code, less sensitive than wall time to other jobs on a shared machine.
  // The rate goes through kIsRate; ns per particle-step is computed here
  // because an inverted rate would be printed in seconds.
  state.counters["particle_steps_per_s"] = benchmark::Counter(particle_steps, benchmark::Counter::kIsRate);
  state.counters["ns_per_particle_step"] = 1e9 * cpu / particle_steps;
  state.counters["particles"] = particles;
  state.counters["check_hash"] = positions_hash(end);
  state.counters["check_mean_y_mm"] = mean_height_mm(end);
  std::string label;
  for (const std::string& o : with_extras(overrides)) label += (label.empty() ? "" : " ") + o;
  state.SetLabel(label);
}

void BM_Step2D(benchmark::State& state) { run_step_benchmark(state, ModelKind::box2d, kWarmup2D, kTimed2D); }
void BM_Step3D(benchmark::State& state) { run_step_benchmark(state, ModelKind::bullet, kWarmup3D, kTimed3D); }

// Steps per repetition, from the timed window and the models' default time steps.
const long kSteps2D = static_cast<long>(kTimed2D / Box2DDef{}.time_step_s + 0.5);
const long kSteps3D = static_cast<long>(kTimed3D / BulletDef{}.time_step_s + 0.5);

BENCHMARK(BM_Step2D)
    ->Name("Step2D")
    ->ArgName("particles")
    ->Arg(500)->Arg(1000)->Arg(2000)->Arg(5000)->Arg(10000)->Arg(20000)
    ->Iterations(kSteps2D)
    ->Unit(benchmark::kMillisecond);

BENCHMARK(BM_Step3D)
    ->Name("Step3D")
    ->ArgName("particles")
    ->Arg(500)->Arg(1000)->Arg(2000)->Arg(5000)
    ->Iterations(kSteps3D)
    ->Unit(benchmark::kMillisecond);

// Opt-in (excluded by the default filter in bench_main.cpp; select with
// --benchmark_filter=Step3DLarge): about a minute per repetition each.
BENCHMARK(BM_Step3D)
    ->Name("Step3DLarge")
    ->ArgName("particles")
    ->Arg(10000)->Arg(20000)
    ->Iterations(kSteps3D)
    ->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace gapflow::bench

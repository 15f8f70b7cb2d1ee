// Shared pieces of the benchmark suite (bench/*.cpp) and of its test
// (tests/test_bench_support.cpp): scenes built from the shipped scenarios/ files
// with --set style overrides (never private copies), a flowing hopper state, and
// physics check values.
//
// Header-only on purpose: the test executable globs tests/test_*.cpp and links
// only the project libraries, so the test can use this without a bench library.
#pragma once

#include "models/registry.hpp"
#include "common/scenario_loader.hpp"
#include "common/cpu_time.hpp"
#include "common/shaking.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <ctime>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#ifndef GAPFLOW_SOURCE_DIR
#error "GAPFLOW_SOURCE_DIR must name the source tree (set by bench/CMakeLists.txt and tests/CMakeLists.txt)"
#endif

namespace gapflow::bench {

// The scenario every benchmark starts from: the paper's medium-sphere discharge.
inline constexpr const char* kPaperMedium = "scenarios/paper/no_obstruction_medium.toml";

inline std::filesystem::path source_path(const std::string& relative) {
  return std::filesystem::path(GAPFLOW_SOURCE_DIR) / relative;
}

// Overrides appended to every scene of the suite (gapflow_bench --set key=value,
// for A/B experiments such as --set model.box2d.continuous_collision=true).
// Empty in a normal run; the study benchmark does not see them.
inline std::vector<std::string>& extra_overrides() {
  static std::vector<std::string> extra;
  return extra;
}

inline std::vector<std::string> with_extras(std::vector<std::string> overrides) {
  overrides.insert(overrides.end(), extra_overrides().begin(), extra_overrides().end());
  return overrides;
}

// Load and compile with overrides (and the extra ones); a bad override is
// reported with its location.
inline CompiledScenario compile_with(const std::filesystem::path& file, const std::vector<std::string>& overrides) {
  const LoadedScenario loaded = load_scenario(file, with_extras(overrides));
  try {
    return compile_scenario(loaded.def);
  } catch (const ScenarioInvalid& e) {
    throw locate(e, loaded);
  }
}

// Overrides that put `count` particles on the board of `file`: up to the file's
// own count the board is unchanged; beyond it the board widens with sqrt(count)
// (the pile keeps the file's shape, and the funnel in front of the gap - where
// the flow is - stays the same) and then lengthens in 5 % steps until the
// packing fits. Deterministic, and printed as each benchmark's label so that a
// scene can be rerun with `gapflow run FILE --set ...`.
inline std::vector<std::string> board_for(const std::filesystem::path& file, int count) {
  const ScenarioDef base = load_scenario(file).def;
  std::vector<std::string> out{"particles.count=" + std::to_string(count)};
  if (count <= base.particles.count) return out;
  const double scale = std::sqrt(static_cast<double>(count) / base.particles.count);
  const double width = 10.0 * std::ceil(base.plane.width_mm * scale / 10.0);  // whole cm: readable labels
  double length = base.plane.length_mm;
  for (int attempt = 0; attempt < 200; ++attempt) {
    std::vector<std::string> trial = out;
    trial.push_back("plane.width_mm=" + std::to_string(static_cast<int>(width)));
    trial.push_back("plane.length_mm=" + std::to_string(static_cast<int>(length)));
    try {
      compile_scenario(load_scenario(file, with_extras(trial)).def);
      return trial;
    } catch (const ScenarioInvalid& e) {
      // Only "does not fit" is cured by a longer board; anything else is a real error.
      if (e.key != "particles.count" && e.key != "plane.length_mm" && e.key != "release.barrier_mm") throw;
    }
    length = 10.0 * std::ceil(length * 1.05 / 10.0);
  }
  throw std::runtime_error("board_for: no board found for " + std::to_string(count) + " particles");
}

// 64-bit FNV-1a, folded to 32 bits so that it survives as a double counter
// (Google Benchmark counters are doubles; 2^32 < 2^53 is exact).
class StateHash {
 public:
  void add(const void* data, std::size_t n) {
    const auto* p = static_cast<const unsigned char*>(data);
    for (std::size_t i = 0; i < n; ++i) h_ = (h_ ^ p[i]) * 0x100000001b3ULL;
  }
  void add(double v) { add(&v, sizeof v); }
  void add(int v) { add(&v, sizeof v); }
  double value() const { return static_cast<double>(static_cast<std::uint32_t>(h_ ^ (h_ >> 32))); }

 private:
  std::uint64_t h_ = 0xcbf29ce484222325ULL;
};

// Bit-exact fingerprint of particle ids and positions: any change to the
// arithmetic of a step (even a reordering that is physically harmless) shows.
inline double positions_hash(const std::vector<ActiveParticle>& particles) {
  StateHash h;
  for (const ActiveParticle& p : particles) {
    h.add(p.id);
    h.add(p.position.x);
    h.add(p.position.y);
  }
  return h.value();
}

// Bit-exact fingerprint of a run's crossings (ids, times, positions).
inline double crossings_hash(const RunRecord& r) {
  StateHash h;
  for (const Crossing& c : r.crossings) {
    h.add(c.id);
    h.add(c.t);
    h.add(c.x);
  }
  return h.value();
}

// A physical (not bit-exact) check: mean height of the particles above the gap
// line, mm. It drifts down as the hopper drains; a speed-up that keeps this
// but changes the hash reordered arithmetic, one that changes this changed physics.
inline double mean_height_mm(const std::vector<ActiveParticle>& particles) {
  if (particles.empty()) return 0.0;
  double sum = 0;
  for (const ActiveParticle& p : particles) sum += p.position.y;
  return 1e3 * sum / static_cast<double>(particles.size());
}

// A hopper that is already flowing: built with the barrier open from the
// packing, then advanced like the run driver does (shakers moved, one step) but
// without measurement, so that a benchmark can time step() alone.
class FlowingHopper {
 public:
  FlowingHopper(const std::filesystem::path& file, const std::vector<std::string>& overrides, ModelKind kind)
      : sc_(std::make_unique<CompiledScenario>(compile_with(file, overrides))),  // sessions keep a reference
        session_(make_session(*sc_, kind)) {
    session_->set_barrier(false);
    session_->set_shake_targets({});
  }

  // Shake targets then one step, as common/simulation.cpp's loop (without measurement).
  void advance(long steps) {
    for (long i = 0; i < steps; ++i) {
      ++step_;
      session_->set_shake_targets(shake_offsets(sc_->def.shaking, step_ * session_->time_step()));
      session_->step();
    }
  }
  // Steps that cover `seconds` of lab time.
  long steps_for(double seconds) const { return std::lround(seconds / session_->time_step()); }

  EngineSession& session() { return *session_; }
  const CompiledScenario& scenario() const { return *sc_; }
  long steps_done() const { return step_; }
  double time() const { return static_cast<double>(step_) * session_->time_step(); }
  std::vector<ActiveParticle> positions() const {
    std::vector<ActiveParticle> out;
    session_->active_particles(out);
    return out;
  }

 private:
  std::unique_ptr<CompiledScenario> sc_;
  std::unique_ptr<EngineSession> session_;
  long step_ = 0;
};

}  // namespace gapflow::bench

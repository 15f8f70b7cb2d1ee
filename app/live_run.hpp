// The simulation behind `gapflow serve`: one run at a time on its own thread,
// paced to real time, steerable from the HTTP handlers (pause, restart, --set
// style changes). Every change is validated by the scenario loader exactly like
// `--set` on the command line and, when valid, restarts the run from release
// with the new scenario; a change of a shaking schedule (shaking.*, except switching a
// shaker on or off, which changes which bodies the engine moves) is taken up by the
// running run at its next step (the driver reads the schedule every step), without a
// restart. State is published as JSON for the page to poll.
#pragma once

#include "models/registry.hpp"

#include <atomic>
#include <condition_variable>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

namespace gapflow {

struct LiveRunDef {
  std::string scenario_file;           // the TOML file
  std::vector<std::string> overrides;  // --set key=value given at start
  ModelKind model = ModelKind::box2d;
  double speed = 1.0;                  // simulated seconds per wall second at most (pacing)
  double publish_hz = 20.0;            // 1/s, state snapshots per wall second
};

class LiveRun {
 public:
  // Loads and compiles the scenario first (throws ScenarioError: exit 2), then starts the thread.
  explicit LiveRun(LiveRunDef def);
  ~LiveRun();  // stops the thread
  LiveRun(const LiveRun&) = delete;
  LiveRun& operator=(const LiveRun&) = delete;

  std::string state_json() const;     // t, J, passed, clogs, rtf, paused, particles, shaking offsets
  std::string geometry_json() const;  // walls, obstruction at rest, gap tips, the current overrides
  void set_paused(bool paused);
  void restart();
  // Apply `key=value` like --set: on success the run restarts (or, for shaking.*, takes
  // the new schedule at its next step) and "" is returned;
  // otherwise the loader's message (with --set:N:column, the key, what is allowed).
  // `restarted` says which of the two happened.
  std::string apply(const std::string& assignment, bool& restarted);

 private:
  void loop();
  void run_once(CompiledScenario& sc);
  void publish(const CompiledScenario& sc, double t, const EngineSession& s, const GapMonitor& m, double rtf);

  LiveRunDef def_;
  mutable std::mutex mutex_;
  std::condition_variable wake_;
  std::vector<std::string> overrides_;  // guarded by mutex_
  std::string state_, geometry_;        // guarded by mutex_
  int generation_ = 0;                  // guarded: bumped by every restart
  bool paused_ = false;                 // guarded
  bool stopping_ = false;               // guarded
  std::optional<ShakingDef> shaking_;   // guarded: a shaking change for the running run to take up
  ShakingDef running_shaking_;          // guarded: the schedule the running run has (or will have)
  std::atomic<bool> cancel_{false};     // the running run must stop (restart or shutdown)
  std::thread thread_;
};

}  // namespace gapflow

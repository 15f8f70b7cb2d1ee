// The pictures and files a run can write while it runs: PNG snapshots, a movie
// and a ParaView series. Fed through the run driver's StepObserver
// (common/simulation.hpp); the engines know nothing of it. A run without outputs
// installs no observer at all, so it pays nothing.
#pragma once

#include "common/simulation.hpp"
#include "view/top_view.hpp"

#include <memory>
#include <string>
#include <vector>

namespace gapflow {

struct RunOutputDef {
  std::vector<double> snapshot_times_s;  // s after release: one PNG at the first step at or after each
  std::string snapshot_dir = ".";        // folder for snapshots (created)
  bool snapshot_on_clog = false;         // one PNG (coloured by state) when each clog is detected
  TopViewDef view;                       // colouring, scale, colour bar range
  std::string movie_path;                // MP4 written through ffmpeg; empty = none
  double movie_fps = 25.0;               // 1/s, frames per second of simulated time (played back at the same rate)
  std::string vtk_dir;                   // ParaView series folder; empty = none
  double vtk_interval_s = 0.1;           // s of simulated time between VTK frames

  bool any() const { return !snapshot_times_s.empty() || snapshot_on_clog || !movie_path.empty() || !vtk_dir.empty(); }
  // Throws std::invalid_argument (exit 2) on bad values or a missing ffmpeg.
  void validate() const;
};

class RunOutputs {
 public:
  RunOutputs(const CompiledScenario& sc, RunOutputDef def);
  ~RunOutputs();
  RunOutputs(const RunOutputs&) = delete;
  RunOutputs& operator=(const RunOutputs&) = delete;

  const StepObserver& observer() const { return observer_; }
  // After the run: close the movie and the ParaView collection; returns one line per output written.
  std::vector<std::string> finish();
  // The PNG files written so far (snapshots and clog snapshots), in order.
  const std::vector<std::string>& written() const;

 private:
  void after_step(double t, const EngineSession& session, const GapMonitor& monitor);
  const FrameState& frame(double t, const EngineSession& session, const GapMonitor& monitor);

  struct Writers;
  const CompiledScenario& sc_;
  RunOutputDef def_;
  std::unique_ptr<Writers> w_;
  StepObserver observer_;
};

}  // namespace gapflow

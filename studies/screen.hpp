// Running a [screen] study (studies/screen_def.hpp) round by round with the racing scheme
// of studies/racing.hpp: every round adds replicates to the cells still alive and to the
// baselines, into the study's store under the usual job keys; the race is then replayed
// from the store. Nothing else is kept: the decisions are a function of the stored runs
// of completed rounds (never of timing or worker count), so a killed screen resumes by
// running the same command, and `gapflow report` re-derives every decision.
#pragma once

#include "studies/racing.hpp"
#include "studies/runner.hpp"
#include "studies/store.hpp"
#include "studies/study.hpp"

#include <iosfwd>
#include <map>
#include <string>
#include <vector>

namespace gapflow {

// One cell of the screen (or a baseline: series "none", one per gap).
struct ScreenCell {
  std::string series;  // shape ("cylinder", "A", "V") or "none"
  int point = 0;       // index in its series' grid
  std::string label;   // "size 3 d, D 2 d, W 4 d"
  std::string axes_json;  // its axis values as stored with its runs: runs are matched by these, not by the
                          // index, which moves when the grid gains or loses a value ("" when infeasible)
  double size_d = 0, distance_d = 0, gap_d = 0;  // in nominal d (size, distance: 0 for a baseline)
  int gap = 0;                                   // index of its gap = its baseline
  bool feasible = true;
  std::string why_not;  // the scenario check that refused it (e.g. the obstruction overlaps a wall)
};

struct ScreenGrid {
  ModelKind model = ModelKind::box2d;
  std::vector<ScreenCell> cells;      // every shape cell, series then point order
  std::vector<ScreenCell> baselines;  // one per gap, gap order
  std::vector<int> raced;             // the feasible cells (indices into cells): RaceInput::cells order
};

// The grid of a screen study, each cell checked by compiling its first job: a cell whose
// obstruction does not fit (overlaps a wall, leaves the board) is infeasible, not an error;
// any other bad scenario throws ScenarioError like expand_jobs.
ScreenGrid screen_grid(const StudyDef& study);

// The jobs of one cell's (or baseline's) replicates [from, to) with `model`.
std::vector<Job> screen_cell_jobs(const StudyDef& study, const ScreenCell& cell, ModelKind model, int from, int to);

// The J the race uses, for cells and baselines alike: J_T, the discharge rate cut at the horizon
// T = the run's run.time_limit_s. A run that emptied (all passed, or all but run.stranded_max left
// behind when the flow stopped for good) enters with its J_paper; one that hit the time limit, or
// that a clog stopped for good with more left behind, with passed / T: J_T = spheres through by
// min(T, t_last) / min(T, t_last). A run stopped early by run.stop_after_no_flow_s counts as passing
// nothing more until T, which is what that stop asserts. At a gap where everything clogs, J_T
// measures how much passes before the clog (Zuriguel et al. 2011's effect). NaN for any other ending
// (run.end = "n_passed"): it says nothing about the horizon, and the race waits on it as missing.
double screen_j(const RunRecord& r, double horizon_s);

// The stored runs of `model` that belong to a raced cell or a baseline and whose job key is the one
// the study asks for now, with their time limit; `ignored` counts those of a cell with another key
// (stored before the study's settings or scenario changed).
struct ScreenRun {
  const StoredRun* run = nullptr;
  const ScreenCell* cell = nullptr;
  double time_limit_s = 0;  // s
};
struct CurrentRuns {
  std::vector<ScreenRun> runs;
  int ignored = 0;
};
CurrentRuns current_screen_runs(const StudyDef& study, const ScreenGrid& grid, const std::vector<StoredRun>& runs,
                                ModelKind model);

// J by replicate index (NaN = not stored) for each cell and baseline, keyed by (series, axes_json),
// from current_screen_runs; replicates >= slots are left out.
using ScreenJ = std::map<std::pair<std::string, std::string>, std::vector<double>>;
ScreenJ screen_j_by_replicate(const StudyDef& study, const ScreenGrid& grid, const std::vector<StoredRun>& runs,
                              ModelKind model, std::size_t slots);
std::vector<double> screen_j_of(const ScreenJ& j, const ScreenCell& c, std::size_t slots);

// J by replicate index for every raced cell and baseline, from the stored runs of the screen's model.
RaceInput screen_race_input(const StudyDef& study, const ScreenGrid& grid, const std::vector<StoredRun>& runs);

// The jobs the race needs next: the missing replicates of the next round (alive cells and
// every baseline), or after the last round the confirmation batch; empty when done.
std::vector<Job> screen_next_jobs(const StudyDef& study, const ScreenGrid& grid, const RaceInput& in,
                                  const RaceState& state);

// Run the screen to its end (or until a job fails or the run is cancelled), printing each
// round's decisions to `log`.
RunnerSummary run_screen(const StudyDef& study, Store& store, const RunnerOptions& options, const JobRunner& run,
                         std::ostream& log);

// "3 d": a length in d as the tables and labels print it.
std::string d_text(double v);

}  // namespace gapflow

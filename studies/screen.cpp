#include "studies/screen.hpp"

#include "studies/confirm.hpp"
#include "studies/screen_check.hpp"

#include <fmt/format.h>

#include <cmath>
#include <map>
#include <ostream>
#include <set>
#include <stdexcept>

namespace gapflow {

std::string d_text(double v) { return fmt::format("{:.3g} d", v); }

namespace {

const SeriesDef& series_named(const StudyDef& study, const std::string& label) {
  for (const SeriesDef& s : study.series)
    if (s.label == label) return s;
  throw std::logic_error("screen study without series " + label);
}

double axis_number(const SweepAxis& a, std::size_t i) { return std::stod(a.values.at(i).toml); }

// A scenario check that says the obstruction does not fit where the cell puts it.
bool infeasible_placement(const ScenarioError& e) {
  return e.key() == "obstruction.distance_mm" || e.key() == "obstruction.lateral_offset_mm";
}

}  // namespace

ScreenGrid screen_grid(const StudyDef& study) {
  if (!study.screen) throw std::logic_error("screen_grid: not a screen study");
  const double d = study.screen->d_mm;
  ScreenGrid g;
  g.model = study.models.at(0);
  const SeriesDef& none = series_named(study, kScreenBaseline);
  const SweepAxis& gaps = none.axes.at(0);
  for (std::size_t w = 0; w < gaps.values.size(); ++w) {
    ScreenCell b{none.label, static_cast<int>(w), "", "", 0, 0, axis_number(gaps, w) / d, static_cast<int>(w), true, ""};
    b.label = "W " + d_text(b.gap_d);
    b.axes_json = point_jobs(study, none, b.point, g.model, 0, 1).front().id.axes_json;  // a bad baseline is an error
    g.baselines.push_back(b);
  }
  for (const SeriesDef& s : study.series) {
    if (s.label == kScreenBaseline) continue;
    const SweepAxis &size = s.axes.at(0), &dist = s.axes.at(1), &gap = s.axes.at(2);
    int point = 0;
    for (std::size_t i = 0; i < size.values.size(); ++i)
      for (std::size_t j = 0; j < dist.values.size(); ++j)
        for (std::size_t w = 0; w < gap.values.size(); ++w, ++point) {
          ScreenCell c{s.label, point, "", "", axis_number(size, i) / d, axis_number(dist, j) / d,
                       axis_number(gap, w) / d, static_cast<int>(w), true, ""};
          c.label = fmt::format("{} size {}, D {}, W {}", s.label, d_text(c.size_d), d_text(c.distance_d),
                                d_text(c.gap_d));
          try {
            c.axes_json = point_jobs(study, s, point, g.model, 0, 1).front().id.axes_json;
          } catch (const ScenarioError& e) {
            if (!infeasible_placement(e)) throw;
            c.feasible = false;
            c.why_not = e.allowed();
          }
          if (c.feasible) g.raced.push_back(static_cast<int>(g.cells.size()));
          g.cells.push_back(std::move(c));
        }
  }
  return g;
}

std::vector<Job> screen_cell_jobs(const StudyDef& study, const ScreenCell& cell, ModelKind model, int from, int to) {
  return point_jobs(study, series_named(study, cell.series), cell.point, model, from, to);
}

double screen_j(const RunRecord& r, double horizon_s) {
  if (r.j_paper) return *r.j_paper;
  if (!(horizon_s > 0)) throw std::logic_error("screen_j: a run without a time limit");
  if (r.end_reason == EndReason::time_limit || r.end_reason == EndReason::permanent_clog) return r.passed / horizon_s;
  return std::nan("");  // another ending (run.end = "n_passed") says nothing about the horizon
}

CurrentRuns current_screen_runs(const StudyDef& study, const ScreenGrid& grid, const std::vector<StoredRun>& runs,
                                ModelKind model) {
  std::map<std::pair<std::string, std::string>, const ScreenCell*> by_axes;  // (series, axes) -> cell
  for (const ScreenCell& c : grid.baselines) by_axes[{c.series, c.axes_json}] = &c;
  for (int i : grid.raced) {
    const ScreenCell& c = grid.cells[static_cast<std::size_t>(i)];
    by_axes[{c.series, c.axes_json}] = &c;
  }
  CurrentRuns out;
  for (const StoredRun& r : runs) {
    if (r.id.study != study.name || r.id.model != to_string(model) || r.id.replicate < 0) continue;
    const auto found = by_axes.find({r.id.series, r.id.axes_json});
    if (found == by_axes.end()) continue;  // a run of a cell the grid no longer has (or of another grid)
    // A run stored before the study's settings changed (another time limit, another model key)
    // has the same cell and replicate but another job key: it must not stand in for the run the
    // study asks for now. One scenario compile per stored run.
    const Job wanted = screen_cell_jobs(study, *found->second, model, r.id.replicate, r.id.replicate + 1).front();
    if (wanted.id.key != r.id.key) {
      out.ignored += 1;
      continue;
    }
    out.runs.push_back({&r, found->second, wanted.time_limit_s});
  }
  return out;
}

ScreenJ screen_j_by_replicate(const StudyDef& study, const ScreenGrid& grid, const std::vector<StoredRun>& runs,
                              ModelKind model, std::size_t slots) {
  ScreenJ j;
  for (const ScreenRun& r : current_screen_runs(study, grid, runs, model).runs) {
    const auto rep = static_cast<std::size_t>(r.run->id.replicate);
    if (rep >= slots) continue;
    auto& v = j[{r.cell->series, r.cell->axes_json}];
    v.resize(slots, std::nan(""));
    v[rep] = screen_j(r.run->record, r.time_limit_s);
  }
  return j;
}

std::vector<double> screen_j_of(const ScreenJ& j, const ScreenCell& c, std::size_t slots) {
  auto it = j.find({c.series, c.axes_json});
  return it != j.end() ? it->second : std::vector<double>(slots, std::nan(""));
}

RaceInput screen_race_input(const StudyDef& study, const ScreenGrid& grid, const std::vector<StoredRun>& runs) {
  const RacingParams& p = study.screen->racing;
  const auto slots = static_cast<std::size_t>(confirmation_end(p));
  const ScreenJ j = screen_j_by_replicate(study, grid, runs, grid.model, slots);
  RaceInput in;
  for (const ScreenCell& b : grid.baselines) {
    in.baseline_names.push_back(b.label);
    in.baselines.push_back(screen_j_of(j, b, slots));
  }
  for (int i : grid.raced) {
    const ScreenCell& c = grid.cells[static_cast<std::size_t>(i)];
    in.cells.push_back({c.label, c.gap, screen_j_of(j, c, slots)});
  }
  return in;
}

std::vector<Job> screen_next_jobs(const StudyDef& study, const ScreenGrid& grid, const RaceInput& in,
                                  const RaceState& state) {
  const RacingParams& p = study.screen->racing;
  const bool confirming = state.screening_done(p);
  const int from = confirming ? p.max : 0;
  const int to = confirming ? p.max + p.confirm : replicates_after_round(p, state.rounds_decided);
  const int baseline_to = confirming ? p.max + baseline_confirm_count(p) : to;
  std::vector<Job> out;
  auto add = [&](const ScreenCell& c, int until) {
    for (Job& job : screen_cell_jobs(study, c, grid.model, from, until)) out.push_back(std::move(job));
  };
  bool any_alive = false;
  for (std::size_t k = 0; k < grid.raced.size(); ++k)
    if (state.alive(static_cast<int>(k))) {
      add(grid.cells[static_cast<std::size_t>(grid.raced[k])], to);
      any_alive = true;
    }
  // Screening: every baseline. Confirmation: only the baselines of gaps with a survivor (the
  // others are compared with nothing; race_budget counts the same).
  if (any_alive)
    for (std::size_t b = 0; b < grid.baselines.size(); ++b)
      if (!confirming || gap_has_survivor(state, in, static_cast<int>(b))) add(grid.baselines[b], baseline_to);
  return out;
}

namespace {

void print_round(std::ostream& log, const RacingParams& p, const RaceState& s, int round, std::size_t n_cells) {
  int kept = 0, dropped = 0;
  for (const RaceDecision& d : s.decisions)
    if (d.round == round) (d.dropped ? dropped : kept) += 1;
  if (kept + dropped == 0) return;  // every cell was dropped before this round
  log << fmt::format("screen round {}/{} ({} replicates per cell, one-sided level {:.2g} per decision): {} kept, "
                     "{} dropped\n",
                     round + 1, race_rounds(p), replicates_after_round(p, round),
                     per_decision_alpha(p, n_cells), kept, dropped);
}

// The runs a screen has asked for, counted once though each round lists the earlier
// rounds' replicates again (resume).
class Tally {
 public:
  explicit Tally(std::set<std::string> stored_before) : stored_before_(std::move(stored_before)) {}
  void add(const RunnerSummary& step, const std::vector<Job>& jobs) {
    for (const Job& j : jobs)
      if (listed_.insert(j.id.key).second) {
        total_.total += 1;
        total_.already_stored += stored_before_.count(j.id.key) ? 1 : 0;
      }
    total_.done_now += step.done_now;
    total_.failed.insert(total_.failed.end(), step.failed.begin(), step.failed.end());
    total_.cancelled = step.cancelled;
  }
  const RunnerSummary& total() const { return total_; }

 private:
  const std::set<std::string> stored_before_;
  std::set<std::string> listed_;
  RunnerSummary total_;
};

// What every stage of a screen runs with.
struct ScreenStage {
  const StudyDef& study;
  const ScreenGrid& grid;
  Store& store;
  const RunnerOptions& options;
  const JobRunner& run;
  std::ostream& log;
};

void log_stale_runs(std::ostream& log, int stale) {
  if (stale > 0)
    log << fmt::format("screen: {} stored runs of this study ignored: their job key is not the one the study asks "
                       "for now (its settings or scenario changed since they ran)\n",
                       stale);
}

// The other model's check of the finished screen (studies/screen_check.hpp).
void run_check(const ScreenStage& r, Tally& tally) {
  const ScreenDef& s = *r.study.screen;
  const RaceInput in = screen_race_input(r.study, r.grid, r.store.load(r.study.name));
  const auto picks = check_picks(s.racing, in, replay_race(s.racing, in), s.check_controls);
  if (!picks) throw std::logic_error("the screen's confirmation is stored but its picks are not decided");
  std::size_t above = 0;
  for (const CheckPick& p : *picks) above += p.role == CheckRole::above ? 1 : 0;
  const std::vector<Job> jobs = check_jobs(r.study, r.grid, *picks);
  r.log << fmt::format("screen check in {}: {} cells above J_0 and {} controls, {} fresh replicates each and per "
                       "baseline (replicates {} to {}): {} jobs\n",
                       to_string(*s.check_model), above, picks->size() - above, s.check_replicates,
                       check_replicate_range(s).from, check_replicate_range(s).to - 1, jobs.size());
  tally.add(r.run(jobs, r.store, r.options), jobs);
}

}  // namespace

RunnerSummary run_screen(const StudyDef& study, Store& store, const RunnerOptions& options, const JobRunner& run,
                         std::ostream& log) {
  const RacingParams& p = study.screen->racing;
  const ScreenGrid grid = screen_grid(study);
  log << fmt::format("screen '{}': {} cells ({} infeasible: the obstruction does not fit), {} gaps; {} rounds of "
                     "{} + {} replicates up to {}, then {} confirmation replicates per survivor and {} per baseline of a gap with a "
                     "survivor\n",
                     study.name, grid.cells.size(), grid.cells.size() - grid.raced.size(), grid.baselines.size(),
                     race_rounds(p), p.initial, p.step, p.max, p.confirm, baseline_confirm_count(p));
  const ScreenStage r{study, grid, store, options, run, log};
  Tally tally(store.keys());
  int printed = 0;
  for (int stage = 0; stage <= race_rounds(p) + 1; ++stage) {
    const std::vector<StoredRun> stored = store.load(study.name);
    if (stage == 0) log_stale_runs(log, current_screen_runs(study, grid, stored, grid.model).ignored);
    const RaceInput in = screen_race_input(study, grid, stored);
    const RaceState state = replay_race(p, in);
    for (; printed < state.rounds_decided; ++printed) print_round(log, p, state, printed, grid.raced.size());
    const std::vector<Job> jobs = screen_next_jobs(study, grid, in, state);
    const bool confirming = state.screening_done(p);
    if (confirming)
      log << fmt::format("screen confirmation: {} jobs (fresh replicates {} to {})\n", jobs.size(), p.max,
                         confirmation_end(p) - 1);
    const RunnerSummary step = run(jobs, store, options);
    tally.add(step, jobs);
    if (step.cancelled || !step.failed.empty()) return tally.total();
    if (confirming) {
      if (study.screen->check_model) run_check(r, tally);
      return tally.total();
    }
  }
  throw std::runtime_error("the screen made no progress: a round's runs are stored but the race cannot decide it");
}

}  // namespace gapflow

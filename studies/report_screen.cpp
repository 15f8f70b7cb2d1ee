// The report of a [screen] study: the race replayed from the store (studies/screen.hpp),
// the final J/J_0 of every survivor on its confirmation runs only, the budget against a
// fixed grid, decisions.csv (every decision) and one heat map per shape and gap.
#include "studies/report.hpp"

#include "common/text_file.hpp"
#include "studies/report_snapshots.hpp"
#include "studies/screen.hpp"
#include "studies/screen_check.hpp"
#include "studies/screen_heatmap.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <ostream>

namespace gapflow {

namespace fs = std::filesystem;

namespace {

using RunsByPoint = std::map<std::pair<std::string, std::string>, std::vector<const StoredRun*>>;  // (series, axes)

// What the report says about one cell.
struct CellResult {
  const ScreenCell* cell = nullptr;
  HeatCell::State state = HeatCell::State::missing;
  int dropped_round = -1;       // 0-based
  RaceDecision last;            // its last decision (dropped: the one that dropped it)
  FinalEstimate final;          // survivors: confirmation runs only
  double clogs_per_100 = -1;    // on the runs the shown J/J_0 comes from
  std::string cut;              // of those runs, how many entered with passed / T and how many spheres they left
  RatioEstimate flowing;        // survivors: J_flowing / J_flowing,0 on the confirmation runs (the mechanism)
  int runs = 0;                 // stored runs of the cell
  double wall_s = 0;            // their wall time (each run is single-threaded: CPU-seconds)
};

// The runs the study asks for now (current_screen_runs: stale keys left out), by cell.
RunsByPoint runs_by_point(const StudyDef& study, const ScreenGrid& grid, const std::vector<StoredRun>& runs,
                          ModelKind model) {
  RunsByPoint out;
  for (const ScreenRun& r : current_screen_runs(study, grid, runs, model).runs)
    out[{r.cell->series, r.cell->axes_json}].push_back(r.run);
  return out;
}

// Clogs per 100 particles passed over the replicates [from, to) of one point.
double clog_rate(const std::vector<const StoredRun*>& runs, int from, int to) {
  double clogs = 0, passed = 0;
  for (const StoredRun* r : runs)
    if (r->id.replicate >= from && r->id.replicate < to) {
      clogs += static_cast<double>(r->record.clogs.size());
      passed += r->record.passed;
    }
  return passed > 0 ? 100 * clogs / passed : -1;
}

// Runs among replicates [from, to) that did not empty (they enter J with passed / T), and the
// spheres they left behind: "2 (1540 left)"; "" when every run emptied.
std::string cut_runs(const std::vector<const StoredRun*>& runs, int from, int to) {
  int cut = 0, left = 0;
  for (const StoredRun* r : runs)
    if (r->id.replicate >= from && r->id.replicate < to && !r->record.j_paper) {
      cut += 1;
      left += r->record.particles - r->record.passed;
    }
  return cut > 0 ? fmt::format("{} ({} left)", cut, left) : "";
}

// J_flowing (crossings per second of flowing time, clogs' time removed) of replicates [from, to).
std::vector<double> flowing_rates(const std::vector<const StoredRun*>& runs, int from, int to) {
  std::vector<double> out;
  for (const StoredRun* r : runs)
    if (r->id.replicate >= from && r->id.replicate < to && r->record.j_flowing) out.push_back(*r->record.j_flowing);
  return out;
}

void add_wall(CellResult& c, const std::vector<const StoredRun*>& runs) {
  for (const StoredRun* r : runs) {
    c.runs += 1;
    c.wall_s += r->record.wall_time_s;
  }
}

std::string fate_text(const CellResult& c, const RacingParams& p) {
  switch (c.state) {
    case HeatCell::State::infeasible: return "infeasible";
    case HeatCell::State::missing: return "not decided yet";
    case HeatCell::State::dropped:
      return fmt::format("dropped after round {} (n = {}): J/J_0 {:.3f}, upper bound {:.3f} ({})",
                         c.dropped_round + 1, c.last.n, c.last.ratio, c.last.upper, c.last.reason);
    case HeatCell::State::final: break;
  }
  if (!c.final.complete)
    return fmt::format("survivor: its {} confirmation runs (or its baseline's {}) are not all stored yet", p.confirm,
                       baseline_confirm_count(p));
  if (!c.final.ratio.valid) return "survivor: J/J_0 undefined (its baseline passed nothing in its confirmation runs)";
  const char* verdict = c.final.simultaneous_above ? "above J_0 (also simultaneously)"
                        : c.final.above            ? "above J_0"
                        : c.final.below            ? "below J_0"
                                                   : "not distinguishable from J_0";
  return fmt::format("survivor: J/J_0 {:.3f} [{:.3f}, {:.3f}], {}", c.final.ratio.ratio, c.final.ratio.lo,
                     c.final.ratio.hi, verdict);
}

std::string map_text(const CellResult& c) {
  switch (c.state) {
    case HeatCell::State::infeasible: return "n/f";
    case HeatCell::State::missing: return "?";
    case HeatCell::State::dropped:  // an upper bound of 0 (nothing passed in any run) or below: "<0.001"
      return fmt::format("<{:.3g} r{}", std::max(c.last.upper, 0.001), c.dropped_round + 1);
    case HeatCell::State::final: break;
  }
  if (!c.final.ratio.valid) return "?";
  const char* mark = c.final.simultaneous_above ? "**" : c.final.above ? "*" : c.final.below ? " -" : "";
  return fmt::format("{:.2f}{}", c.final.ratio.ratio, mark);
}

std::vector<CellResult> cell_results(const StudyDef& study, const ScreenGrid& grid, const RaceInput& in,
                                     const RaceState& state, const RunsByPoint& runs) {
  const RacingParams& p = study.screen->racing;
  std::size_t survivors = 0;
  for (std::size_t k = 0; k < in.cells.size(); ++k) survivors += state.alive(static_cast<int>(k)) ? 1 : 0;
  std::map<int, RaceDecision> last;  // raced index -> its last decision
  for (const RaceDecision& d : state.decisions) last[d.cell] = d;
  std::vector<CellResult> out(grid.cells.size());
  for (std::size_t i = 0; i < grid.cells.size(); ++i) {
    out[i].cell = &grid.cells[i];
    out[i].state = grid.cells[i].feasible ? HeatCell::State::missing : HeatCell::State::infeasible;
    auto it = runs.find({grid.cells[i].series, grid.cells[i].axes_json});
    if (it != runs.end()) add_wall(out[i], it->second);
  }
  for (std::size_t k = 0; k < grid.raced.size(); ++k) {
    CellResult& c = out[static_cast<std::size_t>(grid.raced[k])];
    const auto it = runs.find({c.cell->series, c.cell->axes_json});
    const std::vector<const StoredRun*> none;
    const auto& cell_runs = it != runs.end() ? it->second : none;
    if (last.count(static_cast<int>(k))) c.last = last[static_cast<int>(k)];
    c.dropped_round = state.dropped_after[k];
    if (c.dropped_round >= 0) {
      c.state = HeatCell::State::dropped;
      c.clogs_per_100 = clog_rate(cell_runs, 0, c.last.n);
      c.cut = cut_runs(cell_runs, 0, c.last.n);
    } else if (state.screening_done(p)) {
      c.state = HeatCell::State::final;
      c.final = final_estimate(p, in, static_cast<int>(k), survivors);
      c.clogs_per_100 = clog_rate(cell_runs, p.max, p.max + p.confirm);
      c.cut = cut_runs(cell_runs, p.max, p.max + p.confirm);
      // Whether J rose through fewer clogs or through a faster flow: the flowing rates' ratio.
      const ScreenCell& base = grid.baselines[static_cast<std::size_t>(c.cell->gap)];
      const auto b = runs.find({base.series, base.axes_json});
      if (c.final.complete && b != runs.end())
        c.flowing = ratio_interval(flowing_rates(cell_runs, p.max, p.max + p.confirm),
                                   flowing_rates(b->second, p.max, p.max + baseline_confirm_count(p)), p.confidence);
    }
  }
  return out;
}

// decisions.csv: every decision of every round.
void write_decisions_csv(const fs::path& file, const RaceInput& in, const RaceState& state) {
  write_file_atomically(file, [&](std::ostream& s) {
    s << "round,cell,n,ratio,lower,upper,best_lower,decision\n";
    for (const RaceDecision& d : state.decisions)
      s << fmt::format("{},\"{}\",{},{:.6g},{:.6g},{:.6g},{:.6g},{}\n", d.round + 1,
                       in.cells[static_cast<std::size_t>(d.cell)].name, d.n, d.ratio, d.lower, d.upper, d.best_lower,
                       d.dropped ? "dropped: " + d.reason : d.reason);
  });
}

TextTable budget_table(const StudyDef& study, const ScreenGrid& grid, const std::vector<CellResult>& cells,
                       const RaceInput& in, const RaceState& state, const RunsByPoint& runs) {
  const RacingParams& p = study.screen->racing;
  const RaceBudget b = race_budget(p, state, in);
  double race_cpu = 0, fixed_cpu = 0;
  long stored = 0;
  auto add = [&](int n, double wall, int fixed_replicates) {
    stored += n;
    race_cpu += wall;
    if (n > 0) fixed_cpu += wall / n * fixed_replicates;
  };
  for (const CellResult& c : cells)
    if (c.cell->feasible) add(c.runs, c.wall_s, p.confirm);
  for (const ScreenCell& base : grid.baselines) {
    CellResult r;
    if (auto it = runs.find({base.series, base.axes_json}); it != runs.end()) add_wall(r, it->second);
    add(r.runs, r.wall_s, baseline_confirm_count(p));
  }
  TextTable t;
  t.title = "Budget: the race against a fixed grid at the same final confidence";
  t.header = {"", "runs", "CPU-seconds"};
  t.rows.push_back({"race (screen + confirmation), stored", fmt::format("{}", stored), fmt_num(race_cpu)});
  t.rows.push_back({"race, as planned by its decisions", fmt::format("{}", b.race_runs), ""});
  t.rows.push_back({p.baseline_confirm > 0 ? fmt::format("fixed grid: {} replicates per cell, {} per baseline", p.confirm,
                                                          baseline_confirm_count(p))
                                           : fmt::format("fixed grid: {} replicates per cell and baseline", p.confirm),
                    fmt::format("{}", b.fixed_runs), fmt_num(fixed_cpu)});
  t.rows.push_back({"saved (fixed - race) / fixed",
                    b.fixed_runs > 0 ? fmt::format("{:.0f} %", 100.0 * (b.fixed_runs - stored) / b.fixed_runs) : "",
                    fixed_cpu > 0 ? fmt::format("{:.0f} %", 100.0 * (fixed_cpu - race_cpu) / fixed_cpu) : ""});
  t.notes.push_back(
      "The fixed grid's CPU-seconds are estimated from each cell's mean run cost in this store x the confirmation "
      "replicates. Each run is single-threaded: its wall time is its CPU time.");
  return t;
}

TextTable cells_table(const std::vector<CellResult>& cells, const RacingParams& p) {
  TextTable t;
  t.title = "Cells: fate and final J/J_0 (survivors: confirmation runs only)";
  t.header = {"shape", "size/d", "D/d", "W/d", "runs", "clogs per 100 passed", "not emptied by T", "result",
              "J_flowing/J_flowing,0 [95 %]"};
  for (const CellResult& c : cells)
    t.rows.push_back({c.cell->series, fmt_num(c.cell->size_d, 3), fmt_num(c.cell->distance_d, 3),
                      fmt_num(c.cell->gap_d, 3), fmt::format("{}", c.runs),
                      c.clogs_per_100 >= 0 ? fmt_num(c.clogs_per_100, 3) : "n/a", c.cut, fate_text(c, p),
                      c.flowing.valid ? fmt::format("{:.3f} [{:.3f}, {:.3f}] ({}/{} runs)", c.flowing.ratio,
                                                    c.flowing.lo, c.flowing.hi, c.flowing.n_cell, c.flowing.n_base)
                                      : ""});
  t.notes.push_back(
      "Clogs and \"not emptied by T\" count the runs the cell's J/J_0 comes from (dropped: its screening runs; "
      "survivors: its confirmation runs). A run that did not empty enters with passed / T; the spheres it left "
      "behind say whether a clog held the pile (hundreds) or the run was cut while flowing. The last column (survivors, "
      "once their confirmation runs are all stored; delta-method interval; runs of the cell / of its baseline that "
      "had a flowing rate: a run with no avalanche of two or more spheres has none) reads the mechanism: J_flowing "
      "counts only the time spheres flow (stops longer than the clog threshold removed, and the time before the first "
      "crossing not counted), J_T all of it. J/J_0 above 1 with J_flowing/J_flowing,0 near 1 points to fewer or "
      "shorter clogs (or an earlier first arrival); J_flowing/J_flowing,0 above 1 to a faster flow between them.");
  return t;
}

TextTable rounds_table(const RacingParams& p, const RaceState& s, std::size_t n_cells) {
  TextTable t;
  t.title = "Decisions per round (every decision: decisions.csv)";
  t.header = {"round", "replicates", "one-sided level", "decided", "kept", "dropped"};
  for (int r = 0; r < s.rounds_decided; ++r) {
    int kept = 0, dropped = 0;
    for (const RaceDecision& d : s.decisions)
      if (d.round == r) (d.dropped ? dropped : kept) += 1;
    if (kept + dropped == 0) continue;
    t.rows.push_back({fmt::format("{}", r + 1), fmt::format("{}", replicates_after_round(p, r)),
                      fmt::format("{:.3g}", per_decision_alpha(p, n_cells)), fmt::format("{}", kept + dropped),
                      fmt::format("{}", kept), fmt::format("{}", dropped)});
  }
  return t;
}

// The shapes of the grid, in grid order.
std::vector<std::string> grid_shapes(const ScreenGrid& grid) {
  std::vector<std::string> shapes;
  for (const ScreenCell& c : grid.cells)
    if (std::find(shapes.begin(), shapes.end(), c.series) == shapes.end()) shapes.push_back(c.series);
  return shapes;
}

// One heat map over (D/d, size/d) of one shape at one gap; `fill` draws cell i of the grid.
template <class Fill>
HeatMap grid_map(const ScreenGrid& grid, const std::string& shape, const ScreenCell& gap, Fill&& fill) {
  std::vector<double> xs, ys;
  for (const ScreenCell& c : grid.cells)
    if (c.series == shape) xs.push_back(c.distance_d), ys.push_back(c.size_d);
  for (auto* v : {&xs, &ys}) {
    std::sort(v->begin(), v->end());
    v->erase(std::unique(v->begin(), v->end()), v->end());
  }
  HeatMap m;
  m.ylabel = shape == "cylinder" ? "diameter/d" : "side/d";
  for (double x : xs) m.xs.push_back(fmt::format("{:.3g}", x));
  for (double y : ys) m.ys.push_back(fmt::format("{:.3g}", y));
  for (std::size_t i = 0; i < grid.cells.size(); ++i) {
    const ScreenCell& c = grid.cells[i];
    if (c.series != shape || c.gap != gap.gap) continue;
    HeatCell h = fill(i);
    h.ix = static_cast<std::size_t>(std::lower_bound(xs.begin(), xs.end(), c.distance_d) - xs.begin());
    h.iy = static_cast<std::size_t>(std::lower_bound(ys.begin(), ys.end(), c.size_d) - ys.begin());
    m.cells.push_back(h);
  }
  return m;
}

std::string clog_text(double clogs_per_100) { return clogs_per_100 >= 0 ? fmt::format("{:.2g}", clogs_per_100) : ""; }

// One heat map per shape and gap; the PNG file names.
std::vector<std::string> draw_maps(const ScreenGrid& grid, const std::vector<CellResult>& cells,
                                   const RacingParams& p, const fs::path& out_dir) {
  std::vector<std::string> files;
  for (const std::string& shape : grid_shapes(grid))
    for (const ScreenCell& gap : grid.baselines) {
      HeatMap m = grid_map(grid, shape, gap, [&](std::size_t i) {
        const CellResult& c = cells[i];
        HeatCell h;
        h.state = c.state;
        h.value = c.state == HeatCell::State::final ? c.final.ratio.ratio : c.last.ratio;
        if (c.state == HeatCell::State::final && !c.final.ratio.valid) h.state = HeatCell::State::missing;
        h.text = map_text(c);
        h.side_value = c.clogs_per_100;
        h.side_text = clog_text(c.clogs_per_100);
        return h;
      });
      m.title = fmt::format("{}: J/J_0 at W = {} (confirmation runs)", shape, d_text(gap.gap_d));
      m.legend = fmt::format("* interval above 1 ({:.0f} %), ** also Bonferroni over survivors, - below 1; <u rN: "
                             "dropped after round N (upper bound u), n/f: does not fit, ?: not decided yet",
                             100 * p.confidence);
      const std::string file = fmt::format("screen_map_{}_W{:.3g}d.png", shape, gap.gap_d);
      draw_heatmap_png(m, out_dir / file);
      files.push_back(file);
    }
  return files;
}

// --- The other model's check (studies/screen_check.hpp) ---

// above / at / below J_0, as a word: what the screen said of the cell, and what the check says.
const char* screen_class(CheckRole r) {
  return r == CheckRole::above ? "above" : r == CheckRole::control_at ? "not distinguishable" : "below";
}
const char* check_class(const CheckResult& r) {
  return !r.check.valid ? "?" : r.above ? "above" : r.below ? "below" : "not distinguishable";
}
bool same_class(const CheckResult& r) { return std::string(screen_class(r.pick.role)) == check_class(r); }

struct CheckedCell {
  CheckResult result;
  double clogs_per_100 = -1;  // on its check runs
};

std::vector<CheckedCell> checked_cells(const StudyDef& study, const ScreenGrid& grid, const std::vector<CheckPick>& picks,
                                       const std::vector<StoredRun>& runs) {
  const ScreenDef& s = *study.screen;
  const auto [from, to] = check_replicate_range(s);
  const RunsByPoint by_point = runs_by_point(study, grid, runs, *s.check_model);
  std::vector<CheckedCell> out;
  for (const CheckResult& r : check_results(study, grid, picks, runs)) {
    const ScreenCell& c = picked_cell(grid, r.pick);
    const auto it = by_point.find({c.series, c.axes_json});
    out.push_back({r, it != by_point.end() ? clog_rate(it->second, from, to) : -1});
  }
  return out;
}

TextTable check_table(const StudyDef& study, const ScreenGrid& grid, const std::vector<CheckedCell>& checked) {
  const ScreenDef& s = *study.screen;
  TextTable t;
  t.title = fmt::format("Check in {}: the screen's cells above J_0 and the controls ({} fresh replicates each)",
                        to_string(*s.check_model), s.check_replicates);
  t.header = {"shape", "size/d", "D/d", "W/d", "picked as", fmt::format("J/J_0 {}", to_string(grid.model)),
              fmt::format("J/J_0 {} [{:.0f} %]", to_string(*s.check_model), 100 * s.racing.confidence),
              fmt::format("{} says", to_string(*s.check_model)), "agrees",
              fmt::format("clogs per 100 passed ({})", to_string(*s.check_model))};
  for (const CheckedCell& cc : checked) {
    const CheckResult& r = cc.result;
    const ScreenCell& c = picked_cell(grid, r.pick);
    const bool agrees = same_class(r);
    t.rows.push_back({c.series, fmt_num(c.size_d, 3), fmt_num(c.distance_d, 3), fmt_num(c.gap_d, 3),
                      to_string(r.pick.role), fmt_num(r.pick.screen_ratio, 3),
                      r.check.valid ? fmt::format("{:.3f} {}", r.check.ratio, fmt_ci(r.check.lo, r.check.hi, 3))
                                    : "runs missing",
                      check_class(r), r.check.valid ? (agrees ? "yes" : "no") : "",
                      cc.clogs_per_100 >= 0 ? fmt_num(cc.clogs_per_100, 3) : "n/a"});
  }
  t.notes.push_back(
      "The screen's J/J_0 is its final one (confirmation runs) for survivors and the one at the drop for dropped "
      "cells. \"agrees\": the check puts the cell in the same class (above, not distinguishable from, below J_0) "
      "as the screen.");
  return t;
}

std::string check_summary(const StudyDef& study, const ScreenGrid& grid, const std::vector<CheckedCell>& checked) {
  const ScreenDef& s = *study.screen;
  int above = 0, at = 0, below = 0, above_done = 0, held = 0, valid = 0, agree = 0;
  std::vector<double> screen, check;
  for (const CheckedCell& cc : checked) {
    const CheckResult& r = cc.result;
    const CheckRole role = r.pick.role;
    (role == CheckRole::above ? above : role == CheckRole::control_at ? at : below) += 1;
    if (!r.check.valid) continue;
    ++valid;
    above_done += role == CheckRole::above ? 1 : 0;
    held += role == CheckRole::above && r.above ? 1 : 0;
    agree += same_class(r) ? 1 : 0;
    if (std::isfinite(r.pick.screen_ratio)) screen.push_back(r.pick.screen_ratio), check.push_back(r.check.ratio);
  }
  const double rho = screen.size() >= 3 ? spearman_correlation(screen, check) : std::nan("");
  const std::string model = to_string(*s.check_model);
  return fmt::format(
      "**Check in {}** (cells picked from the stored {} runs once the confirmation was complete: the {} survivors "
      "whose final interval lies above 1, and {} controls ({} asked for): {} at J_0 (the closest to J/J_0 = 1 among "
      "cells shown neither above nor below), {} shown below J_0 (spread over their range); each with its gap's "
      "baseline, {} fresh replicates at indices {} to {}, seeds that neither the race nor the confirmation used). "
      "{} of {} checked cells have all their runs. The effect holds (the {} interval lies above 1) in **{} of {}** "
      "such cells the screen put above J_0; {} of {} are in the same class in both models; rank correlation "
      "(Spearman) of J/J_0 between the models over them: {}. Read with care: the screen's J/J_0 of a cell picked "
      "because its interval lay above 1 is selected on (it tends to be high: winner's curse), while the {} numbers "
      "are not; cells at one gap share their baseline runs; a control \"agrees\" also when {} replicates cannot "
      "tell it from J_0.",
      model, to_string(grid.model), above, at + below, s.check_controls, at, below, s.check_replicates,
      check_replicate_range(s).from, check_replicate_range(s).to - 1, valid,
      checked.size(), model, held, above_done, agree, valid,
      std::isnan(rho) ? std::string("n/a (fewer than 3 cells)") : fmt::format("{:.2f} ({} cells)", rho, screen.size()),
      model, s.check_replicates);
}

// The check's heat maps: one per shape and gap with a checked cell; unchecked cells grey.
std::vector<std::string> draw_check_maps(const StudyDef& study, const ScreenGrid& grid,
                                         const std::vector<CheckedCell>& checked, const fs::path& out_dir) {
  const ScreenDef& s = *study.screen;
  std::map<std::size_t, const CheckedCell*> by_cell;  // grid cell index -> check
  for (const CheckedCell& cc : checked)
    by_cell[static_cast<std::size_t>(grid.raced.at(static_cast<std::size_t>(cc.result.pick.raced)))] = &cc;
  std::vector<std::string> files;
  for (const std::string& shape : grid_shapes(grid))
    for (const ScreenCell& gap : grid.baselines) {
      bool any = false;
      for (const auto& [i, cc] : by_cell) any |= grid.cells[i].series == shape && grid.cells[i].gap == gap.gap;
      if (!any) continue;
      HeatMap m = grid_map(grid, shape, gap, [&](std::size_t i) {
        HeatCell h;
        h.state = grid.cells[i].feasible ? HeatCell::State::missing : HeatCell::State::infeasible;
        const auto it = by_cell.find(i);
        if (it == by_cell.end() || !it->second->result.check.valid) return h;
        const CheckResult& r = it->second->result;
        h.state = HeatCell::State::final;
        h.value = r.check.ratio;
        h.text = fmt::format("{:.2f}{}", r.check.ratio, r.above ? "*" : r.below ? " -" : "");
        h.side_value = it->second->clogs_per_100;
        h.side_text = clog_text(h.side_value);
        return h;
      });
      m.title = fmt::format("{}: J/J_0 in {} at W = {} (check runs)", shape, to_string(*s.check_model),
                            d_text(gap.gap_d));
      m.legend = fmt::format("* interval above 1 ({:.0f} %), - below 1; grey: not checked, n/f: does not fit",
                             100 * s.racing.confidence);
      const std::string file = fmt::format("screen_check_{}_{}_W{:.3g}d.png", to_string(*s.check_model), shape,
                                           gap.gap_d);
      draw_heatmap_png(m, out_dir / file);
      files.push_back(file);
    }
  return files;
}

void add_check(ExperimentSection& sec, const StudyDef& study, const ScreenGrid& grid, const RaceInput& in,
               const RaceState& state, const std::vector<StoredRun>& runs, const fs::path& out_dir, bool plots) {
  const ScreenDef& s = *study.screen;
  const auto picks = check_picks(s.racing, in, state, s.check_controls);
  if (!picks) {
    sec.paragraphs.push_back(fmt::format("**Check in {}**: not started (the screen's confirmation is not complete).",
                                         to_string(*s.check_model)));
    return;
  }
  const std::vector<CheckedCell> checked = checked_cells(study, grid, *picks, runs);
  sec.paragraphs.push_back(check_summary(study, grid, checked));
  CellResult cost;  // every stored check run, cells and baselines (each single-threaded: wall = CPU)
  for (const auto& [cell, cell_runs] : runs_by_point(study, grid, runs, *s.check_model)) add_wall(cost, cell_runs);
  sec.paragraphs.push_back(fmt::format("The check's cost so far: {} {} runs, {} CPU-seconds.", cost.runs,
                                       to_string(*s.check_model), fmt_num(cost.wall_s)));
  sec.tables.push_back(check_table(study, grid, checked));
  if (!plots) return;
  std::string list;
  for (const std::string& f : draw_check_maps(study, grid, checked, out_dir)) list += fmt::format("![{}]({})\n", f, f);
  if (!list.empty())
    sec.paragraphs.push_back(fmt::format("Check heat maps ({}; left J/J_0, right clogs per 100 passed):\n\n",
                                         to_string(*s.check_model)) +
                             list);
}

}  // namespace

ExperimentSection screen_section(const StudyDef& study, const std::vector<StoredRun>& runs, const fs::path& out_dir,
                                 bool plots) {
  const RacingParams& p = study.screen->racing;
  const ScreenGrid grid = screen_grid(study);
  const RaceInput in = screen_race_input(study, grid, runs);
  const RaceState state = replay_race(p, in);
  const RunsByPoint by_point = runs_by_point(study, grid, runs, grid.model);
  const std::vector<CellResult> cells = cell_results(study, grid, in, state, by_point);

  ExperimentSection s;
  s.title = "Screen: where does an obstruction raise J?";
  s.paragraphs.push_back(fmt::format(
      "{} cells ({} infeasible: the obstruction does not fit there), {} gaps, {} model. Racing: every cell gets {} "
      "replicates, then {} more per round up to {} ({} rounds). After each round a cell is **dropped** when the "
      "one-sided upper bound of J/J_0 (delta method, Welch degrees of freedom) at level {} = {:.3g} is below {}{}: "
      "{} (Bonferroni). {}",
      grid.cells.size(), grid.cells.size() - grid.raced.size(), grid.baselines.size(), to_string(grid.model),
      p.initial, p.step, p.max, race_rounds(p), p.family ? "alpha / (cells x rounds)" : "alpha / rounds",
      per_decision_alpha(p, grid.raced.size()), p.drop_below,
      p.best_margin ? fmt::format(", or below the best cell's lower bound minus {}", *p.best_margin) : "",
      p.family ? fmt::format("with probability >= {:.0f} % no cell whose true J/J_0 is >= {} is dropped",
                             100 * (1 - p.alpha), p.drop_below)
               : fmt::format("a cell whose true J/J_0 is >= {} is dropped with probability <= {:.0f} % (per cell, "
                             "not for the whole map: scope = \"family\" for that)",
                             p.drop_below, 100 * p.alpha) +
                   (p.best_margin ? "; this bound covers the drop_below rule only: the best_margin rule has no "
                                    "error guarantee"
                                  : ""),
      state.screening_done(p) ? "" : fmt::format("**Incomplete**: {} of {} rounds decided.", state.rounds_decided,
                                                 race_rounds(p))));
  s.paragraphs.push_back(fmt::format(
      "Final statistics: each survivor gets {} **fresh** replicates (indices {} to {}){}; its J/J_0 "
      "and {:.0f} % interval use those runs only, never the runs that decided its fate, so the selection does not "
      "bias them (no correction needed). `*`: interval above 1; `**`: above 1 also at the Bonferroni level over the "
      "survivors (a family-wise statement for the whole map). A run that did not empty (time limit, or stopped by "
      "a clog for good) enters the race and the final J with its throughput over the horizon, passed / "
      "run.time_limit_s: J is the discharge rate cut at the time limit, for cells and baselines alike. The generic "
      "tables above pool screening and confirmation runs: read this "
      "section's numbers instead.",
      p.confirm, p.max, p.max + p.confirm - 1,
      p.baseline_confirm > 0 ? fmt::format(", the baseline of each gap with a survivor {} (indices {} to {}: it is "
                                           "compared with every survivor at its gap)", baseline_confirm_count(p), p.max,
                                           p.max + baseline_confirm_count(p) - 1)
                             : " and so does the baseline of each gap with a survivor",
      100 * p.confidence));
  write_decisions_csv(out_dir / "decisions.csv", in, state);
  s.tables.push_back(budget_table(study, grid, cells, in, state, by_point));
  s.tables.push_back(rounds_table(p, state, grid.raced.size()));
  s.tables.push_back(cells_table(cells, p));
  if (plots) {
    std::string list;
    for (const std::string& f : draw_maps(grid, cells, study.screen->racing, out_dir)) list += fmt::format("![{}]({})\n", f, f);
    s.paragraphs.push_back("Heat maps (left J/J_0, right clogs per 100 particles passed):\n\n" + list);
  }
  if (study.screen->check_model) add_check(s, study, grid, in, state, runs, out_dir, plots);
  return s;
}

ExperimentSection screen_report_section(const ReportRequest& request, const fs::path& db,
                                        const std::vector<StoredRun>& runs, const fs::path& out_dir,
                                        std::ostream& log) {
  try {
    const std::string name = runs.empty() ? std::string() : runs.front().id.study;
    const StudyDef study = study_for_snapshots(db, request.study, name, request.quick);
    if (study.screen) return screen_section(study, runs, out_dir, request.plots);
    throw std::invalid_argument("the study file has no [screen] table");
  } catch (const std::exception& e) {
    log << "warning: no screen section: " << e.what() << "\n";
    ExperimentSection s;
    s.title = "Screen";
    s.paragraphs.push_back(fmt::format("The screen's grid could not be rebuilt: {}", e.what()));
    return s;
  }
}

}  // namespace gapflow

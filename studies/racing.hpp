// Racing (successive halving by confidence bounds) for a screen of many cells against a
// baseline: every cell gets `initial` replicates; after each round, a cell whose upper
// confidence bound on J/J_0 is below `drop_below` (or below the best cell's lower bound
// minus `best_margin`) is dropped; the others get `step` more replicates, up to `max`.
// The survivors and the baselines of their gaps then get `confirm` FRESH replicates (indices max ..
// max + confirm - 1; a baseline `baseline_confirm` if set), and the final J/J_0 and its interval use those alone: runs that
// decided a cell's fate never enter its final statistics, so selection cannot bias them.
//
// Pure statistics: no simulation, no store. The screen driver (studies/screen.hpp) feeds it
// J values by replicate index; the tests feed it a generator with known means. The race is
// a function of the data of completed rounds only (round r reads the first n_r replicates
// of each cell, whatever else is there), so it is deterministic and can be replayed.
//
// Error rate (`scope`): each drop decision uses a one-sided bound at level alpha / rounds
// ("cell": a cell whose true J/J_0 is >= drop_below is dropped with probability <= alpha),
// or alpha / (cells x rounds) ("family": the probability that ANY such cell is dropped is
// <= alpha), by Bonferroni, up to the normal approximation of the ratio (both tested).
// The guarantee covers the drop_below rule only: best_margin (drop a cell below the best
// cell's lower bound minus a margin) saves runs but bounds no error rate.
#pragma once

#include <optional>
#include <string>
#include <vector>

namespace gapflow {

struct RacingParams {
  int initial = 3;           // screening replicates per cell in the first round
  int step = 3;              // replicates added per round
  int max = 12;              // screening replicates per cell at most
  int confirm = 10;          // fresh replicates per survivor (and per baseline, unless baseline_confirm) (final statistics)
  int baseline_confirm = 0;  // fresh replicates per baseline in the confirmation; 0: confirm. A baseline is compared
                             // with every survivor at its gap: Dunnett's allocation gives it ~sqrt(k) x confirm for k
                             // survivors there, and a shared baseline's noise then moves those k ratios less
  double alpha = 0.05;       // error of the drop decisions (dimensionless), per cell or per family (scope)
  bool family = false;       // scope: false = per cell (alpha / rounds), true = family-wise (alpha / (cells x rounds))
  double drop_below = 1.0;   // J/J_0: drop a cell whose upper bound is below this
  std::optional<double> best_margin;  // J/J_0: also drop when upper < best lower bound - margin (absent: off)
  double confidence = 0.95;  // two-sided level of the final intervals
};

// Fresh replicates of a baseline in the confirmation (baseline_confirm, or confirm when 0), and the
// replicate index after the whole confirmation batch (the first index a later check may use).
int baseline_confirm_count(const RacingParams& p);
int confirmation_end(const RacingParams& p);

// Rounds of screening (>= 1) and the replicates a cell has after round r (0-based).
int race_rounds(const RacingParams& p);
int replicates_after_round(const RacingParams& p, int round);
// Per-decision one-sided error level: alpha / rounds, or alpha / (cells x rounds) when family-wise.
double per_decision_alpha(const RacingParams& p, std::size_t n_cells);

// J/J_0 from two samples (delta method, Welch-Satterthwaite degrees of freedom):
//   R = mean(cell) / mean(base),  se = sqrt(s_c^2/n_c + R^2 s_0^2/n_0) / mean(base).
struct RatioEstimate {
  int n_cell = 0, n_base = 0;
  double ratio = 0, se = 0, df = 0;  // df = +inf when both samples have zero variance
  double lo = 0, hi = 0;             // the interval asked for (see ratio_interval / ratio_upper)
  bool valid = false;                // needs >= 2 values in each sample and mean(base) > 0
};
// Two-sided interval at `confidence`.
RatioEstimate ratio_interval(const std::vector<double>& cell, const std::vector<double>& base, double confidence);
// One-sided bounds: hi is the (1 - a) upper bound, lo the (1 - a) lower bound.
RatioEstimate ratio_bounds(const std::vector<double>& cell, const std::vector<double>& base, double a);

// What the race reads: J per replicate index (entry i = replicate i; NaN = not stored).
struct RaceCell {
  std::string name;          // for the decisions table
  int baseline = 0;          // index into RaceInput::baselines (the cell's gap)
  std::vector<double> j;     // particles/s
};
struct RaceInput {
  std::vector<std::string> baseline_names;
  std::vector<std::vector<double>> baselines;  // J_0 per baseline, by replicate index
  std::vector<RaceCell> cells;
};

// One decision: cell `cell` after round `round` (0-based) on its first n replicates.
struct RaceDecision {
  int round = 0, cell = 0, n = 0;
  double ratio = 0, lower = 0, upper = 0;  // one-sided bounds at per_decision_alpha
  double best_lower = 0;                   // the largest lower bound of that round
  bool dropped = false;
  std::string reason;                      // "kept", "upper < 1", "upper < best lower - margin"
};

struct RaceState {
  int rounds_decided = 0;          // rounds whose data were complete and are decided
  int screened_replicates = 0;     // replicates per baseline (and per surviving cell) the decided rounds read
  std::vector<int> dropped_after;  // per cell: round it was dropped after, -1 = alive
  std::vector<RaceDecision> decisions;
  bool screening_done(const RacingParams& p) const { return rounds_decided >= race_rounds(p); }
  bool alive(int cell) const { return dropped_after[static_cast<std::size_t>(cell)] < 0; }
};

// Decide every round whose data are complete (every alive cell and every baseline has
// its first n_r replicates), in order; stop at the first incomplete round.
RaceState replay_race(const RacingParams& p, const RaceInput& in);

// The final statistics of one cell: J/J_0 on the confirmation replicates only (the cell's
// [max, max + confirm), its baseline's [max, max + baseline_confirm_count)), two-sided at
// p.confidence; invalid when they are missing.
// `simultaneous_above`: the lower bound at confidence 1 - (1 - c)/n_survivors is above 1
// (Bonferroni over the survivors: a family-wise statement for the whole map).
struct FinalEstimate {
  bool complete = false;  // every confirmation run of the cell and its baseline is stored (the ratio
                          // may still be invalid: a baseline that passed nothing has no J/J_0)
  RatioEstimate ratio;
  bool above = false, below = false;  // the interval excludes 1, above / below
  bool simultaneous_above = false;
};
FinalEstimate final_estimate(const RacingParams& p, const RaceInput& in, int cell, std::size_t n_survivors);

// Replicates [from, to) of a sample that are all present (NaN = missing); empty when any is missing.
std::vector<double> replicate_slice(const std::vector<double>& j, int from, int to);

// Runs of the race against a fixed grid that gives every cell `confirm` replicates and every
// baseline baseline_confirm_count (the same final confidence per cell, with no screening).
struct RaceBudget {
  long race_runs = 0;   // screening + confirmation, cells and baselines
  long fixed_runs = 0;  // cells x confirm + baselines x baseline_confirm_count
};
// A baseline gets its confirmation runs only when some cell of its gap survived (screen_next_jobs).
RaceBudget race_budget(const RacingParams& p, const RaceState& s, const RaceInput& in);

// Runs of the fixed grid (cells x confirm + baselines x baseline_confirm_count), and the most a
// race can take (no cell dropped: every cell and baseline screened to max, then confirmed).
long fixed_grid_runs(const RacingParams& p, std::size_t n_cells, std::size_t n_baselines);
long most_race_runs(const RacingParams& p, std::size_t n_cells, std::size_t n_baselines);

// Whether some cell at baseline `b`'s gap is alive (its baseline then needs confirmation runs).
bool gap_has_survivor(const RaceState& s, const RaceInput& in, int b);

}  // namespace gapflow

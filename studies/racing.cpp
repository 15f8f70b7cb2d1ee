#include "studies/racing.hpp"

#include "common/statistics.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace gapflow {

int race_rounds(const RacingParams& p) {
  const int extra = std::max(0, p.max - p.initial);
  return 1 + (extra + p.step - 1) / std::max(1, p.step);
}

int replicates_after_round(const RacingParams& p, int round) {
  return std::min(p.max, p.initial + std::max(0, round) * p.step);
}

double per_decision_alpha(const RacingParams& p, std::size_t n_cells) {
  const double cells = p.family ? static_cast<double>(std::max<std::size_t>(1, n_cells)) : 1.0;
  return p.alpha / (cells * race_rounds(p));
}

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// The ratio, its standard error and Welch-Satterthwaite degrees of freedom.
RatioEstimate ratio_core(const std::vector<double>& cell, const std::vector<double>& base) {
  RatioEstimate r;
  r.n_cell = static_cast<int>(cell.size());
  r.n_base = static_cast<int>(base.size());
  if (r.n_cell < 2 || r.n_base < 2) return r;
  const Summary c = summarize(cell), b = summarize(base);
  if (!(b.mean > 0)) return r;
  r.ratio = c.mean / b.mean;
  const double a1 = c.sd * c.sd / r.n_cell;                     // var of mean(cell)
  const double a0 = r.ratio * r.ratio * b.sd * b.sd / r.n_base;  // R^2 var of mean(base)
  r.se = std::sqrt(a1 + a0) / b.mean;
  const double den = a1 * a1 / (r.n_cell - 1) + a0 * a0 / (r.n_base - 1);
  r.df = den > 0 ? (a1 + a0) * (a1 + a0) / den : kInf;
  r.valid = true;
  return r;
}

double t_quantile(double p, double df) { return std::isinf(df) ? normal_quantile(p) : student_t_quantile(p, df); }

}  // namespace

RatioEstimate ratio_bounds(const std::vector<double>& cell, const std::vector<double>& base, double a) {
  RatioEstimate r = ratio_core(cell, base);
  if (!r.valid) return r;
  const double t = r.se > 0 ? t_quantile(1 - a, r.df) : 0.0;
  r.lo = r.ratio - t * r.se;
  r.hi = r.ratio + t * r.se;
  return r;
}

RatioEstimate ratio_interval(const std::vector<double>& cell, const std::vector<double>& base, double confidence) {
  return ratio_bounds(cell, base, (1 - confidence) / 2);
}

std::vector<double> replicate_slice(const std::vector<double>& j, int from, int to) {
  std::vector<double> out;
  if (from < 0 || to > static_cast<int>(j.size())) return out;
  for (int i = from; i < to; ++i) {
    if (std::isnan(j[static_cast<std::size_t>(i)])) return {};
    out.push_back(j[static_cast<std::size_t>(i)]);
  }
  return out;
}

RaceState replay_race(const RacingParams& p, const RaceInput& in) {
  RaceState s;
  s.dropped_after.assign(in.cells.size(), -1);
  const double a = per_decision_alpha(p, in.cells.size());
  for (int round = 0; round < race_rounds(p); ++round) {
    const int n = replicates_after_round(p, round);
    std::vector<std::vector<double>> base(in.baselines.size());
    for (std::size_t b = 0; b < in.baselines.size(); ++b) base[b] = replicate_slice(in.baselines[b], 0, n);
    // Complete round: every alive cell and its baseline have the first n replicates.
    std::vector<RaceDecision> round_decisions;
    bool complete = true;
    for (std::size_t c = 0; c < in.cells.size() && complete; ++c) {
      if (!s.alive(static_cast<int>(c))) continue;
      const RaceCell& cell = in.cells[c];
      const std::vector<double> x = replicate_slice(cell.j, 0, n);
      const std::vector<double>& y = base.at(static_cast<std::size_t>(cell.baseline));
      if (x.empty() || y.empty()) {
        complete = false;
        break;
      }
      const RatioEstimate r = ratio_bounds(x, y, a);
      RaceDecision d;
      d.round = round;
      d.cell = static_cast<int>(c);
      d.n = n;
      // A ratio that is undefined (fewer than 2 runs, J_0 = 0) decides nothing: kept.
      d.ratio = r.valid ? r.ratio : std::nan("");
      d.lower = r.valid ? r.lo : -kInf;
      d.upper = r.valid ? r.hi : kInf;
      round_decisions.push_back(d);
    }
    if (!complete || round_decisions.empty()) break;
    double best_lower = -kInf;
    for (const RaceDecision& d : round_decisions) best_lower = std::max(best_lower, d.lower);
    const bool last = round + 1 == race_rounds(p);
    for (RaceDecision& d : round_decisions) {
      d.best_lower = best_lower;
      if (d.upper < p.drop_below) {
        d.dropped = true;
        d.reason = "upper < drop_below";
      } else if (p.best_margin && d.upper < best_lower - *p.best_margin) {
        d.dropped = true;
        d.reason = "upper < best lower - margin";
      } else {
        d.reason = last ? "kept: confirm" : "kept";
      }
      if (d.dropped) s.dropped_after[static_cast<std::size_t>(d.cell)] = round;
      s.decisions.push_back(d);
    }
    s.rounds_decided = round + 1;
    s.screened_replicates = n;
    const bool any_alive = std::any_of(s.dropped_after.begin(), s.dropped_after.end(), [](int r) { return r < 0; });
    if (!any_alive) {
      s.rounds_decided = race_rounds(p);  // nothing left to screen
      break;
    }
  }
  return s;
}

int baseline_confirm_count(const RacingParams& p) { return p.baseline_confirm > 0 ? p.baseline_confirm : p.confirm; }

int confirmation_end(const RacingParams& p) { return p.max + std::max(p.confirm, baseline_confirm_count(p)); }

FinalEstimate final_estimate(const RacingParams& p, const RaceInput& in, int cell, std::size_t n_survivors) {
  FinalEstimate f;
  const RaceCell& c = in.cells.at(static_cast<std::size_t>(cell));
  const std::vector<double> x = replicate_slice(c.j, p.max, p.max + p.confirm);
  const std::vector<double> y =
      replicate_slice(in.baselines.at(static_cast<std::size_t>(c.baseline)), p.max, p.max + baseline_confirm_count(p));
  f.complete = !x.empty() && !y.empty();
  f.ratio = ratio_interval(x, y, p.confidence);
  if (!f.ratio.valid) return f;
  f.above = f.ratio.lo > 1;
  f.below = f.ratio.hi < 1;
  const double a = (1 - p.confidence) / static_cast<double>(std::max<std::size_t>(1, n_survivors));
  f.simultaneous_above = ratio_interval(x, y, 1 - a).lo > 1;
  return f;
}

bool gap_has_survivor(const RaceState& s, const RaceInput& in, int b) {
  for (std::size_t c = 0; c < in.cells.size(); ++c)
    if (in.cells[c].baseline == b && s.alive(static_cast<int>(c))) return true;
  return false;
}

RaceBudget race_budget(const RacingParams& p, const RaceState& s, const RaceInput& in) {
  RaceBudget b;
  const int screened = s.screened_replicates;
  const std::size_t n_cells = in.cells.size(), n_baselines = in.baselines.size();
  std::size_t survivors = 0;
  for (std::size_t c = 0; c < n_cells; ++c) {
    const int dropped = s.dropped_after[c];
    b.race_runs += dropped >= 0 ? replicates_after_round(p, dropped) : screened;
    survivors += dropped < 0 ? 1 : 0;
  }
  b.race_runs += static_cast<long>(n_baselines) * screened + static_cast<long>(survivors) * p.confirm;
  for (std::size_t g = 0; g < n_baselines; ++g)
    b.race_runs += gap_has_survivor(s, in, static_cast<int>(g)) ? baseline_confirm_count(p) : 0;
  b.fixed_runs = fixed_grid_runs(p, n_cells, n_baselines);
  return b;
}

long fixed_grid_runs(const RacingParams& p, std::size_t n_cells, std::size_t n_baselines) {
  return static_cast<long>(n_cells) * p.confirm + static_cast<long>(n_baselines) * baseline_confirm_count(p);
}

long most_race_runs(const RacingParams& p, std::size_t n_cells, std::size_t n_baselines) {
  return static_cast<long>(n_cells + n_baselines) * p.max + fixed_grid_runs(p, n_cells, n_baselines);
}

}  // namespace gapflow

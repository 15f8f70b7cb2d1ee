#include "studies/steady_analysis.hpp"

#include <cmath>

namespace gapflow {

std::optional<SteadyPointStatistics> steady_point_statistics(const std::vector<RunRecord>& runs) {
  SteadyPointStatistics s;
  for (const RunRecord& r : runs) {
    const std::optional<SteadyStateEstimate> e = steady_state_of(r);
    if (!e) continue;
    ++s.n_runs;
    s.runs.push_back(*e);
    if (!e->valid) continue;
    ++s.n_valid;
    s.total_window_s += e->window_s;
    s.n_autocorrelated += e->autocorrelated ? 1 : 0;
    s.n_transient_at_limit += e->transient_at_limit ? 1 : 0;
  }
  if (s.n_runs == 0) return std::nullopt;
  if (s.n_valid == 0) return s;
  double crossings = 0, truncation = 0, var = 0, var_terms = 0;
  for (const SteadyStateEstimate& e : s.runs) {
    if (!e.valid) continue;
    crossings += e.crossings;
    truncation += e.truncation_s;
    const double w = e.window_s / s.total_window_s;
    const double se = e.half_width_per_s / student_t_975(static_cast<std::size_t>(e.batches - 1));
    const double v = w * w * se * se;
    var += v;
    var_terms += v * v / (e.batches - 1);
  }
  s.j_per_s = crossings / s.total_window_s;
  s.mean_truncation_s = truncation / static_cast<double>(s.n_valid);
  if (var_terms > 0) {
    s.dof = var * var / var_terms;
    s.half_width_per_s = student_t_quantile(0.975, s.dof) * std::sqrt(var);
  } else {
    s.half_width_per_s = 0;  // every batch of every run had the same count
  }
  return s;
}

}  // namespace gapflow

// J_steady of a report point: the re-injected runs' steady-state estimates
// (common/steady_state.hpp), computed from the stored crossings at analysis time (the
// store keeps no steady-state column), pooled over the point's runs.
#pragma once

#include "common/run_record.hpp"
#include "common/statistics.hpp"
#include "common/steady_state.hpp"

#include <optional>
#include <vector>

namespace gapflow {

// Pooled over the valid runs i (window w_i, crossings N_i, batch-means standard error se_i =
// half-width_i / t_{0.975, k_i - 1}):
//   J = sum N_i / sum w_i   (throughput over all windows = sum (w_i/W) J_i, W = sum w_i)
//   se^2 = sum (w_i/W)^2 se_i^2, half-width = t_{0.975, nu} se, nu by Welch-Satterthwaite
//   nu = se^4 / sum ((w_i/W)^2 se_i^2)^2 / (k_i - 1); one run gives its own interval back.
struct SteadyPointStatistics {
  std::size_t n_runs = 0;             // runs that re-injected
  std::size_t n_valid = 0;            // of those, with an estimate (why_not otherwise)
  std::vector<SteadyStateEstimate> runs;
  double j_per_s = kNaN;              // particles/s
  double half_width_per_s = kNaN;     // particles/s, 95 %
  double dof = kNaN;                  // nu
  double mean_truncation_s = kNaN;    // s, mean MSER-5 truncation over valid runs
  double total_window_s = 0;          // s, W
  std::size_t n_autocorrelated = 0;   // runs whose batch means stayed autocorrelated
  std::size_t n_transient_at_limit = 0;  // runs whose transient did not end in their first half
  Interval interval() const { return {j_per_s - half_width_per_s, j_per_s + half_width_per_s}; }
};

// Nothing when no run of the point re-injected.
std::optional<SteadyPointStatistics> steady_point_statistics(const std::vector<RunRecord>& runs);

}  // namespace gapflow

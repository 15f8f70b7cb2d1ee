// Steady-state flow rate of a re-injected run (protocol.reinject_passed): the pile is
// kept at a fixed number of particles, so after a start-up transient the crossings form a
// stationary process whose rate J_steady is the answer. Pure functions of the crossing
// times; no engine.
//
// The estimator, step by step (estimate_steady_state):
//  1. Counts per bin: the crossings in bins of bin_s seconds from release to the last
//     whole bin before the end of the run.
//  2. Transient: MSER-5 (White 1997, Simulation 69:323; White, Cobb & Spratt 2000, Proc.
//     Winter Simulation Conf. 755). The bin counts are grouped in batches of 5 bins, Z_j,
//     j = 0..m-1; for each truncation d (batches dropped from the start)
//         MSER(d) = sum_{j>=d} (Z_j - mean_{j>=d} Z)^2 / (m - d)^2
//     (the squared standard error of the truncated mean, with n in the denominator twice);
//     the truncation is the d that minimises it, searched over d <= m/2 only: near the end
//     the statistic rests on a handful of batches and its minimum means nothing (White et
//     al. 2000). A minimum at that bound means the transient was not seen to end
//     (transient_at_limit): the run was too short. Known weakness: a clog early in the run
//     looks like a slow start to MSER and can be cut off with the transient, leaving fewer
//     clogs in the window than the process has (results/steady_state: 300-sphere run); the
//     fix to try is MSER on the flowing bins only, clog intervals left out.
//  3. Window: from the truncation time to the end of the run. J_steady = crossings in the
//     window / window length. Clogs inside the window are INCLUDED (their time counts, no
//     crossings): J_steady is throughput, particles per second of running, the steady-state
//     counterpart of J_paper = N / T, which also includes its clogs. (J_flowing is the one
//     that removes clogs; a window ending in an unbroken clog lowers J_steady, as it should.)
//  4. Interval: non-overlapping batch means (e.g. Law & Kelton, Simulation Modeling and
//     Analysis, sec. 9.5.3). The window is cut into k equal batches (so the batch length
//     grows with the window); each batch's rate is its count / its length; J is their mean
//     and the 95 % half-width is t_{0.975, k-1} s_batch / sqrt(k) (Student-t, Boost.Math).
//     Batch means are nearly independent only when a batch is much longer than the
//     process's correlation time (the shaking period, clog cycles): the lag-1
//     autocorrelation r1 of the batch means is tested, and while it is significantly
//     positive (r1 > z_{1-alpha} / sqrt(k), Bartlett's large-sample sd of r1 under
//     independence; one-sided: only positive correlation makes the interval too narrow)
//     the batches are made longer, k -> floor(2k/3) (30, 20, 13, 10 by default), not below
//     min_batches. If r1 is still significant at min_batches, the estimate says so
//     (autocorrelated): its interval is too narrow; run longer.
#pragma once

#include "common/run_record.hpp"

#include <optional>
#include <string>
#include <vector>

namespace gapflow {

struct SteadyStateDef {
  double bin_s = 0.1;                 // s, width of the count bins MSER reads
  int mser_batch_bins = 5;            // bins per MSER batch (MSER-5)
  int max_batches = 30;               // batch-means batches to start with
  int min_batches = 10;               // fewest batches (each merge step: k -> floor(2k/3))
  double autocorrelation_alpha = 0.05;  // one-sided level of the lag-1 test
  double level = 0.95;                // two-sided confidence of the interval
  double fixed_truncation_s = -1;     // s; < 0: detect the transient (MSER-5); >= 0: cut here instead
};

struct SteadyStateEstimate {
  bool valid = false;
  std::string why_not;                // when not valid: what was missing
  double j_per_s = 0;                 // particles/s, crossings in the window / window
  double half_width_per_s = 0;        // particles/s, half-width of the `level` interval
  double truncation_s = 0;            // s after release, start of the window (MSER-5)
  double window_s = 0;                // s, from truncation_s to the end of the run
  int crossings = 0;                  // in the window
  int batches = 0;                    // k used for the interval
  double batch_s = 0;                 // s, length of each batch
  double lag1_autocorrelation = 0;    // of the k batch means
  bool autocorrelated = false;        // r1 still significant at min_batches: interval too narrow
  bool transient_at_limit = false;    // MSER minimum at its search bound (half the run): run longer
  double clogged_s = 0;               // s of clogs inside the window (counted in J: throughput)
  double relative_half_width() const { return j_per_s > 0 ? half_width_per_s / j_per_s : 0; }
};

// J_steady of a run whose crossing times (s after release, any order) are `times` and which
// ended at t_end_s. `clogs` (the record's, may be empty) only feed clogged_s.
SteadyStateEstimate estimate_steady_state(const std::vector<double>& times, double t_end_s,
                                          const std::vector<Clog>& clogs = {}, const SteadyStateDef& def = {});

// The estimate of a record of a re-injected run (reinjected > 0), over its whole length,
// or up to `until_s` (s after release) to ask what a shorter run would have given;
// nothing for a run that did not re-inject (its pile drains: there is no steady state).
std::optional<SteadyStateEstimate> steady_state_of(const RunRecord& r, std::optional<double> until_s = std::nullopt,
                                                   const SteadyStateDef& def = {});

// The "J (steady)" line of the run summary (with warnings on their own lines).
std::string steady_state_line(const SteadyStateEstimate& e);

// Pieces, exposed for tests.
// Counts of `times` in bins [i w, (i+1) w), i < floor(t_end / w).
std::vector<double> bin_counts(const std::vector<double>& times, double t_end_s, double bin_s);
// MSER-b truncation of a series: how many leading OBSERVATIONS to drop (a multiple of
// batch), and whether the minimum lay at the search bound (half the batches).
struct MserTruncation {
  std::size_t drop = 0;
  bool at_limit = false;
};
MserTruncation mser_truncation(const std::vector<double>& series, int batch = 5);
// Lag-1 autocorrelation sum (x_i - m)(x_{i+1} - m) / sum (x_i - m)^2 (0 for constant data).
double lag1_autocorrelation(const std::vector<double>& x);

}  // namespace gapflow

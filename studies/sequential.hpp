// Sequential replication: a study asks for a target interval width instead of a fixed count
// ([study] replicates_target_halfwidth, replicates_max, replicates_batch; study.hpp).
//
// Rounds. Every point runs its minimum (`replicates`); then, round by round, each point whose
// Student-t 95 % interval of mean J (the study's [report] j, over its runs with J defined) is
// still wider than +-target x |mean| gets `batch` more replicates, up to the cap. A round is
// decided from the store after the previous round has finished, from replicates 0 .. n-1 of
// each point only, and replicates are numbered (seeded) in order: the set of runs a study ends
// with depends on the seeds alone, never on the number of workers, their timing or on
// interruptions (a resumed study re-decides the same rounds from the stored runs and skips them).
//
// Honesty. Stopping when the interval is narrow enough (optional stopping) favours samples whose
// sd happens to be low, so the final interval covers slightly less than 95 %. Kept small by a
// minimum of kMinSequentialReplicates (10) before the first look and measured by simulation
// (tests/test_sequential.cpp: coverage of the final Student-t interval over many synthetic
// studies, normal and skewed J; README "Sequential replication" gives the figures). A point
// that reaches the cap keeps its (wider) interval: the cap only costs width, not coverage.
#pragma once

#include "common/statistics.hpp"
#include "studies/jobs.hpp"
#include "studies/runner.hpp"
#include "studies/store.hpp"

#include <iosfwd>
#include <vector>

namespace gapflow {

// What one point does next, from the J values (defined ones) of its replicates 0 .. n-1.
struct SequentialStep {
  double relative_halfwidth = kNaN;  // t_{0.975, m-1} sd / sqrt(m) / |mean| over the m values; +inf for m < 2
  bool reached = false;              // relative_halfwidth <= target
  int next = 0;                      // replicates after this round: n when reached or capped, else n + batch (capped)
};
SequentialStep sequential_step(const std::vector<double>& j, int n, int max_replicates, const SequentialDef& def);

// Per (series, point, model) of the stored runs: one more than the highest replicate stored (the
// counts expand_jobs needs to rebuild the jobs of every round, e.g. for the report's snapshots).
ReplicateCounts stored_replicate_counts(const std::vector<StoredRun>& runs);

// After the study's first round (summary `first`), the further rounds until every point has
// reached the target or its cap (or a run failed, or the study was cancelled). Progress and a
// final per-point line go to `log` (nullptr: silent). Returns the summary of all rounds.
RunnerSummary run_sequential_rounds(const StudyDef& study, Store& store, const RunnerOptions& options,
                                    RunnerSummary first, const JobRunner& run, std::ostream* log);

}  // namespace gapflow

// Sharding a job list for a cluster: share I of K is a stable partition of the jobs by
// job key, balanced by each job's expected cost (Job::expected_cost).
//
// The partition depends only on the set of (key, expected cost) pairs, never on the
// order of the list or on the machine: every array task, rank or later re-plan of
// the same study computes the same shares. Each share runs into its own store
// (which resumes like any store); `gapflow merge` joins them by key (merge.hpp).
// Works on any vector<Job> (a study, its confirm stage, a calibration).
#pragma once

#include "studies/jobs.hpp"
#include "studies/store.hpp"

#include <iosfwd>
#include <string>
#include <string_view>
#include <vector>

namespace gapflow {

// Share `index` (1-based) of `count`.
struct ShardSpec {
  int index = 1;
  int count = 1;
  std::string label() const;  // "I/K"
};

// "I/K" with 1 <= I <= K <= 100000; a bad text throws std::invalid_argument saying what is allowed.
ShardSpec parse_shard(std::string_view text);

// The share (1..count) of each job, in the order of `jobs`: greedy longest-first (jobs by expected
// cost, largest first, ties by key) onto the least loaded share (ties: the lowest). Jobs of unknown
// cost (0) count as the mean known cost (1 when none is known), so equal jobs deal out round robin.
std::vector<int> assign_shards(const std::vector<Job>& jobs, int count);

// The jobs of one share, in their order in `jobs`.
std::vector<Job> jobs_of_shard(const std::vector<Job>& jobs, const ShardSpec& shard);

// Every job with its share, as a store's plan table keeps it.
std::vector<PlannedJob> plan_of(const std::vector<Job>& jobs, int count);

// The job list as JSON lines, one job a line: key, share, expected cost, identity, and the resolved
// scenario (file + overrides, which `gapflow check FILE --set ... --print` expands). Only the jobs
// of `only` when given.
void write_plan(std::ostream& out, const std::vector<Job>& jobs, int count, const ShardSpec* only = nullptr);

}  // namespace gapflow

// Merging the stores of a sharded study (shard.hpp) back into one, by job key.
//
// Idempotent: a run already in the output with the same results and code version is
// skipped, so merging twice (or merging a store into itself) changes nothing. A run
// whose key is stored with different results, a different identity or a different
// code version is a conflict: reported, never written (the output keeps its run).
// Provenance (shard, host, code version, and the store merged from) goes with each run.
// The plan tables of the shard stores say which jobs the whole study has, so a merge
// of a half-finished set lists what is missing.
#pragma once

#include "studies/store.hpp"

#include <filesystem>
#include <string>
#include <vector>

namespace gapflow {

struct MergeConflict {
  std::string key;
  std::filesystem::path source;  // the store whose run was refused
  std::string what;              // what differs, e.g. "j_paper/crossings/... differ", "code version a vs b"
};

struct MergeSummary {
  int added = 0;      // runs new to the output
  int identical = 0;  // runs the output already had, identical (merging again adds nothing)
  std::vector<MergeConflict> conflicts;
  int planned = 0;                   // jobs in the plan tables (0: no source recorded a plan)
  std::vector<PlannedJob> missing;   // planned, but in no store: run their shares again (they resume)
};

// Merge `sources` into `out` (one transaction per source). A source that does not exist is
// std::invalid_argument (nothing is merged).
MergeSummary merge_stores(Store& out, const std::vector<std::filesystem::path>& sources);

// Why two stored runs of one key are not the same run ("" when they are).
std::string run_difference(const StoredRun& a, const StoredRun& b);

// Run by run: keys only in a, only in b, and keys whose runs differ (run_difference), as lines.
std::vector<std::string> compare_stores(const Store& a, const Store& b);

}  // namespace gapflow

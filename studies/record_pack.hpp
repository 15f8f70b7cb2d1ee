// A RunRecord as bytes: how an MPI worker sends a finished run to the rank that
// stores it, and how a merge tells two runs of one key apart (same_results).
// One field list (record_pack.cpp) serves both, so a field added to RunRecord
// and forgotten there fails the round-trip test rather than vanishing silently.
#pragma once

#include "common/run_record.hpp"
#include "studies/store.hpp"

#include <string>

namespace gapflow {

std::string pack_record(const RunRecord& r);
// Throws std::runtime_error on bytes that are not a packed record (truncated, trailing bytes).
RunRecord unpack_record(const std::string& bytes);

// Whether two runs of one job report the same results: every field of the record, bit for bit,
// except wall_time_s (the machine's speed, not a result).
bool same_results(const RunRecord& a, const RunRecord& b);

// The first field in which the identities of two stored runs differ ("" when none does).
std::string identity_difference(const JobIdentity& a, const JobIdentity& b);

}  // namespace gapflow

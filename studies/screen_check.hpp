// The other model's check of a finished screen (issue 18: "confirm in 3D every cell the 2D
// screen puts significantly above J_0, and a control set below and at J_0, with fresh seeds").
//
// Once the screen's confirmation batch is complete, the cells to check are a function of the
// stored runs alone: every survivor whose final interval lies above 1, plus `check_controls`
// cells that are not above: (n + 1) / 2 "at J_0" (the closest to J/J_0 = 1 among the cells not
// shown above or below: survivors not distinguishable from J_0, cells dropped by a rule that does
// not show them below 1), the rest spread over the cells shown below J_0 (dropped with an upper
// bound under 1, or a final interval under 1); fewer when there are not enough such cells. Each picked cell and the baseline of
// its gap get `check_replicates` runs of `check_model` at replicate indices that neither the
// race nor the confirmation used (fresh particle sets and seeds), and J/J_0 in that model is
// the same ratio of means with its delta-method interval as the screen's (studies/racing.hpp).
#pragma once

#include "studies/screen.hpp"

#include <optional>
#include <string>
#include <vector>

namespace gapflow {

enum class CheckRole { above, control_at, control_below };
const char* to_string(CheckRole r);

struct CheckPick {
  int raced = 0;     // index into ScreenGrid::raced (= RaceInput::cells)
  CheckRole role = CheckRole::above;
  double screen_ratio = 0;  // J/J_0 in the screen: the final one (survivors) or at the drop
};

// The check's replicate indices [from, to): after the race's and the confirmation's.
struct ReplicateRange {
  int from = 0, to = 0;
};
ReplicateRange check_replicate_range(const ScreenDef& s);

// The cells to check, in raced order within each role (above, at, below); nullopt while the
// screen's confirmation is incomplete (the picks depend on it).
std::optional<std::vector<CheckPick>> check_picks(const RacingParams& p, const RaceInput& in, const RaceState& state,
                                                  int controls);

// The grid cell of a pick.
const ScreenCell& picked_cell(const ScreenGrid& grid, const CheckPick& pick);

// The check model's jobs: each pick and the baseline of each gap it lies at.
std::vector<Job> check_jobs(const StudyDef& study, const ScreenGrid& grid, const std::vector<CheckPick>& picks);

// One checked cell: its screen verdict and its J/J_0 in the check model (valid once every one
// of its and its baseline's check runs is stored).
struct CheckResult {
  CheckPick pick;
  RatioEstimate check;   // two-sided at the screen's confidence
  bool above = false, below = false;  // the check interval excludes 1
};
std::vector<CheckResult> check_results(const StudyDef& study, const ScreenGrid& grid,
                                       const std::vector<CheckPick>& picks, const std::vector<StoredRun>& runs);

}  // namespace gapflow

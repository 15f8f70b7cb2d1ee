// Screen -> confirm: rank the screened points of a study by mean J and run the
// best ones again with the confirming model (usually 3D), so that a cheap 2D
// screen over a fine grid ends in a few expensive 3D runs.
#pragma once

#include "studies/jobs.hpp"
#include "studies/store.hpp"
#include "studies/study.hpp"

#include <optional>
#include <string>
#include <vector>

namespace gapflow {

// A run's J of one kind ("paper" | "flowing" | "mid", as in the study file); nullopt where undefined.
std::optional<double> run_j(const RunRecord& r, const std::string& kind);

struct RankedPoint {
  std::string series;
  int point = 0;
  std::string point_label;
  double mean_j = 0;  // particles/s, over the screen's replicates
  int runs = 0;
  int runs_with_j = 0;  // runs in which the ranking J is defined (J_paper: the board emptied)
};

// The screen's points (the study's own models, from the store), best first: points
// with J in every run by mean J, then points where some run had no J (never emptied).
std::vector<RankedPoint> rank_screened_points(const StudyDef& study, const std::vector<StoredRun>& runs);

// The confirming jobs: study.confirm.replicates runs with study.confirm.model for
// each of the top study.confirm.top ranked points (job keys as in expand_jobs), with
// [confirm] set applied after the study's and the series' overrides. The points of
// the report's baseline series are always confirmed as well (J/J_0 per model).
std::vector<Job> confirm_jobs(const StudyDef& study, const std::vector<RankedPoint>& ranked);

}  // namespace gapflow

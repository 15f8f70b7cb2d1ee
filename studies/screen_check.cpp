#include "studies/screen_check.hpp"

#include <algorithm>
#include <cmath>
#include <set>

namespace gapflow {

const char* to_string(CheckRole r) {
  switch (r) {
    case CheckRole::above: return "above J_0 in the screen";
    case CheckRole::control_at: return "control: at J_0";
    case CheckRole::control_below: return "control: below J_0";
  }
  return "?";
}

int first_check_replicate(const RacingParams& p) { return p.max + p.confirm; }

namespace {

struct Candidate {
  int raced = 0;
  double ratio = 0;
};

// `n` of the sorted candidates, spread evenly (n = 1: the median), in raced order.
std::vector<Candidate> spread(std::vector<Candidate> sorted, int n) {
  std::vector<Candidate> out;
  const auto size = static_cast<int>(sorted.size());
  n = std::min(n, size);
  for (int k = 0; k < n; ++k) out.push_back(sorted[static_cast<std::size_t>((2 * k + 1) * size / (2 * n))]);
  std::sort(out.begin(), out.end(), [](const Candidate& a, const Candidate& b) { return a.raced < b.raced; });
  return out;
}

}  // namespace

std::optional<std::vector<CheckPick>> check_picks(const RacingParams& p, const RaceInput& in, const RaceState& state,
                                                  int controls) {
  if (!state.screening_done(p)) return std::nullopt;
  std::size_t survivors = 0;
  for (std::size_t c = 0; c < in.cells.size(); ++c) survivors += state.alive(static_cast<int>(c)) ? 1 : 0;
  std::vector<double> last_ratio(in.cells.size(), std::nan(""));
  for (const RaceDecision& d : state.decisions) last_ratio[static_cast<std::size_t>(d.cell)] = d.ratio;
  std::vector<CheckPick> above;
  std::vector<Candidate> at, below;
  for (int c = 0; c < static_cast<int>(in.cells.size()); ++c) {
    if (!state.alive(c)) {
      below.push_back({c, last_ratio[static_cast<std::size_t>(c)]});
      continue;
    }
    const FinalEstimate f = final_estimate(p, in, c, survivors);
    if (!f.ratio.valid) return std::nullopt;  // its confirmation runs are not all stored
    if (f.above)
      above.push_back({c, CheckRole::above, f.ratio.ratio});
    else
      (f.below ? below : at).push_back({c, f.ratio.ratio});
  }
  // At J_0: the survivors closest to 1. Below: spread over the range, so that the controls
  // are typical of what the screen rejected rather than its borderline cases only.
  std::stable_sort(at.begin(), at.end(),
                   [](const Candidate& a, const Candidate& b) { return std::abs(a.ratio - 1) < std::abs(b.ratio - 1); });
  at.resize(std::min(at.size(), static_cast<std::size_t>((controls + 1) / 2)));
  std::sort(at.begin(), at.end(), [](const Candidate& a, const Candidate& b) { return a.raced < b.raced; });
  std::stable_sort(below.begin(), below.end(), [](const Candidate& a, const Candidate& b) {
    return a.ratio < b.ratio || (!std::isnan(a.ratio) && std::isnan(b.ratio));
  });
  const int n_below = controls - static_cast<int>(at.size());
  std::vector<CheckPick> out = above;
  for (const Candidate& c : at) out.push_back({c.raced, CheckRole::control_at, c.ratio});
  for (const Candidate& c : spread(below, n_below)) out.push_back({c.raced, CheckRole::control_below, c.ratio});
  return out;
}

namespace {

const ScreenCell& picked_cell(const ScreenGrid& grid, const CheckPick& pick) {
  return grid.cells.at(static_cast<std::size_t>(grid.raced.at(static_cast<std::size_t>(pick.raced))));
}

}  // namespace

std::vector<Job> check_jobs(const StudyDef& study, const ScreenGrid& grid, const std::vector<CheckPick>& picks) {
  const ScreenDef& s = *study.screen;
  const int from = first_check_replicate(s.racing), to = from + s.check_replicates;
  std::vector<Job> out;
  std::set<int> gaps;
  for (const CheckPick& pick : picks) {
    const ScreenCell& cell = picked_cell(grid, pick);
    gaps.insert(cell.gap);
    for (Job& j : screen_cell_jobs(study, cell, *s.check_model, from, to)) out.push_back(std::move(j));
  }
  for (int g : gaps)
    for (Job& j : screen_cell_jobs(study, grid.baselines.at(static_cast<std::size_t>(g)), *s.check_model, from, to))
      out.push_back(std::move(j));
  return out;
}

std::vector<CheckResult> check_results(const StudyDef& study, const ScreenGrid& grid,
                                       const std::vector<CheckPick>& picks, const std::vector<StoredRun>& runs) {
  const ScreenDef& s = *study.screen;
  const int from = first_check_replicate(s.racing), to = from + s.check_replicates;
  const auto slots = static_cast<std::size_t>(to);
  const ScreenJ j = screen_j_by_replicate(study, grid, runs, *s.check_model, slots);
  std::vector<CheckResult> out;
  for (const CheckPick& pick : picks) {
    const ScreenCell& cell = picked_cell(grid, pick);
    CheckResult r;
    r.pick = pick;
    r.check = ratio_interval(replicate_slice(screen_j_of(j, cell, slots), from, to),
                             replicate_slice(screen_j_of(j, grid.baselines.at(static_cast<std::size_t>(cell.gap)),
                                                         slots),
                                             from, to),
                             s.racing.confidence);
    r.above = r.check.valid && r.check.lo > 1;
    r.below = r.check.valid && r.check.hi < 1;
    out.push_back(r);
  }
  return out;
}

}  // namespace gapflow

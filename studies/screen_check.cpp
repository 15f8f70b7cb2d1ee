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

ReplicateRange check_replicate_range(const ScreenDef& s) {
  const int from = confirmation_end(s.racing);  // after every cell's and baseline's confirmation runs
  return {from, from + s.check_replicates};
}

namespace {

struct Candidate {
  int raced = 0;
  double ratio = 0;
};

// What the screen concluded of each raced cell: above J_0 (its final interval), shown below it
// (dropped with an upper bound under 1, or a final interval under 1), or neither ("at": not
// distinguishable, or dropped by a rule that does not show it below 1, e.g. best_margin). A cell
// whose J/J_0 is undefined (its baseline passed nothing) is in none. nullopt while a survivor's
// confirmation runs are missing.
struct ScreenClasses {
  std::vector<Candidate> above, at, below;
};
std::optional<ScreenClasses> screen_classes(const RacingParams& p, const RaceInput& in, const RaceState& state) {
  std::size_t survivors = 0;
  for (std::size_t c = 0; c < in.cells.size(); ++c) survivors += state.alive(static_cast<int>(c)) ? 1 : 0;
  std::vector<const RaceDecision*> last(in.cells.size(), nullptr);
  for (const RaceDecision& d : state.decisions) last[static_cast<std::size_t>(d.cell)] = &d;
  ScreenClasses out;
  for (int c = 0; c < static_cast<int>(in.cells.size()); ++c) {
    if (!state.alive(c)) {
      const RaceDecision& d = *last[static_cast<std::size_t>(c)];
      if (!std::isnan(d.ratio)) (d.upper < 1 ? out.below : out.at).push_back({c, d.ratio});
      continue;
    }
    const FinalEstimate f = final_estimate(p, in, c, survivors);
    if (!f.complete) return std::nullopt;
    if (!f.ratio.valid) continue;
    (f.above ? out.above : f.below ? out.below : out.at).push_back({c, f.ratio.ratio});
  }
  return out;
}

bool by_cell(const Candidate& a, const Candidate& b) { return a.raced < b.raced; }

// The n candidates closest to J/J_0 = 1, in cell order.
std::vector<Candidate> closest_to_one(std::vector<Candidate> v, std::size_t n) {
  std::stable_sort(v.begin(), v.end(),
                   [](const Candidate& a, const Candidate& b) { return std::abs(a.ratio - 1) < std::abs(b.ratio - 1); });
  v.resize(std::min(v.size(), n));
  std::sort(v.begin(), v.end(), by_cell);
  return v;
}

// n candidates spread evenly over their range of J/J_0 (n = 1: the median), in cell order: the
// controls are then typical of what the screen rejected, not only its borderline cases.
std::vector<Candidate> spread(std::vector<Candidate> v, std::size_t n) {
  std::stable_sort(v.begin(), v.end(), [](const Candidate& a, const Candidate& b) { return a.ratio < b.ratio; });
  n = std::min(n, v.size());
  std::vector<Candidate> out;
  for (std::size_t k = 0; k < n; ++k) out.push_back(v[(2 * k + 1) * v.size() / (2 * n)]);
  std::sort(out.begin(), out.end(), by_cell);
  return out;
}

}  // namespace

std::optional<std::vector<CheckPick>> check_picks(const RacingParams& p, const RaceInput& in, const RaceState& state,
                                                  int controls) {
  if (!state.screening_done(p)) return std::nullopt;
  const std::optional<ScreenClasses> classes = screen_classes(p, in, state);
  if (!classes) return std::nullopt;
  std::vector<CheckPick> out;
  for (const Candidate& c : classes->above) out.push_back({c.raced, CheckRole::above, c.ratio});
  const auto n = static_cast<std::size_t>(controls);
  const std::vector<Candidate> at = closest_to_one(classes->at, (n + 1) / 2);
  for (const Candidate& c : at) out.push_back({c.raced, CheckRole::control_at, c.ratio});
  for (const Candidate& c : spread(classes->below, n - at.size()))
    out.push_back({c.raced, CheckRole::control_below, c.ratio});
  return out;
}

const ScreenCell& picked_cell(const ScreenGrid& grid, const CheckPick& pick) {
  return grid.cells.at(static_cast<std::size_t>(grid.raced.at(static_cast<std::size_t>(pick.raced))));
}

std::vector<Job> check_jobs(const StudyDef& study, const ScreenGrid& grid, const std::vector<CheckPick>& picks) {
  const ScreenDef& s = *study.screen;
  const auto [from, to] = check_replicate_range(s);
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
  const auto [from, to] = check_replicate_range(s);
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

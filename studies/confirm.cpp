#include "studies/confirm.hpp"

#include <algorithm>
#include <map>
#include <set>

namespace gapflow {

std::optional<double> run_j(const RunRecord& r, const std::string& kind) {
  if (kind == "flowing") return r.j_flowing;
  if (kind == "mid") return r.j_mid;
  return r.j_paper;
}

std::vector<RankedPoint> rank_screened_points(const StudyDef& study, const std::vector<StoredRun>& runs) {
  std::set<std::string> screen_models;
  for (ModelKind m : study.models) screen_models.insert(to_string(m));
  std::map<std::pair<std::string, int>, RankedPoint> points;
  std::map<std::pair<std::string, int>, std::pair<double, int>> sums;  // sum of J, runs with J
  for (const StoredRun& r : runs) {
    if (r.id.study != study.name || !screen_models.count(r.id.model)) continue;
    const auto k = std::make_pair(r.id.series, r.id.point);
    RankedPoint& p = points[k];
    p.series = r.id.series;
    p.point = r.id.point;
    p.point_label = r.id.point_label;
    ++p.runs;
    if (auto j = run_j(r.record, study.confirm.rank_by)) {
      sums[k].first += *j;
      sums[k].second += 1;
    }
    p.runs_with_j = sums[k].second;
  }
  std::vector<RankedPoint> out;
  for (auto& [k, p] : points) {
    const auto& [sum, n] = sums[k];
    p.mean_j = n > 0 ? sum / n : -1.0;
    out.push_back(p);
  }
  // A candidate must have a J in every screening run: a point where some runs never
  // emptied would otherwise rank by its lucky runs alone. Then best mean J first; ties
  // by series label (alphabetical), then point, so the choice is deterministic.
  std::stable_sort(out.begin(), out.end(), [](const RankedPoint& a, const RankedPoint& b) {
    const bool a_complete = a.runs_with_j == a.runs, b_complete = b.runs_with_j == b.runs;
    if (a_complete != b_complete) return a_complete;
    return a.mean_j > b.mean_j;
  });
  return out;
}

std::vector<Job> confirm_jobs(const StudyDef& study, const std::vector<RankedPoint>& ranked) {
  std::set<std::pair<std::string, int>> chosen;
  // The top candidates (the baseline is not a candidate), and the baseline itself:
  // J/J_0 of a confirmed point needs J_0 of its own model.
  int candidates = 0;
  for (const RankedPoint& p : ranked) {
    if (p.series == study.report.baseline) {
      chosen.insert({p.series, p.point});
    } else if (candidates < study.confirm.top) {
      chosen.insert({p.series, p.point});
      ++candidates;
    }
  }
  StudyDef confirming = study;
  confirming.models = {study.confirm.model};
  confirming.replicates = study.confirm.replicates;
  // The confirming model runs as the study defines it ([per_model] set kept, e.g. a 2D
  // confirmation of a 2D screen keeps its effects), on every point, with [confirm] set last.
  for (auto& [model, plan] : confirming.per_model) {
    plan.replicates.reset();
    plan.thin = 1;
    plan.set.insert(plan.set.end(), study.confirm.set.begin(), study.confirm.set.end());
  }
  if (!confirming.per_model.count(study.confirm.model))
    for (SeriesDef& s : confirming.series) s.set.insert(s.set.end(), study.confirm.set.begin(), study.confirm.set.end());
  std::vector<Job> out;
  for (Job& j : expand_jobs(confirming))
    if (chosen.count({j.id.series, j.id.point})) out.push_back(std::move(j));
  return out;
}

}  // namespace gapflow

#include "studies/sequential.hpp"

#include "studies/confirm.hpp"

#include <fmt/format.h>

#include <cmath>
#include <limits>
#include <ostream>

namespace gapflow {

SequentialStep sequential_step(const std::vector<double>& j, int n, int max_replicates, const SequentialDef& def) {
  SequentialStep s;
  const Summary t = summarize(j);
  s.relative_halfwidth = t.n >= 2 && t.mean != 0 ? t.ci95_half / std::abs(t.mean)
                                                 : std::numeric_limits<double>::infinity();
  s.reached = s.relative_halfwidth <= def.target_halfwidth;
  s.next = s.reached || n >= max_replicates ? n : std::min(n + std::max(1, def.batch), max_replicates);
  return s;
}

namespace {

using PointId = ReplicateCounts::key_type;  // (series, point, model)

// Per point of the current job list: its replicate count and the J of those replicates.
struct PointRuns {
  std::string label;
  int planned = 0, stored = 0;
  std::vector<double> j;
};

std::map<PointId, PointRuns> points_of_round(const std::vector<Job>& jobs, const std::vector<StoredRun>& runs,
                                             const std::string& j_kind) {
  std::map<PointId, PointRuns> out;
  std::map<std::string, PointId> point_of_key;
  for (const Job& job : jobs) {
    const PointId id{job.id.series, job.id.point, job.id.model};
    out[id].label = job.id.point_label;
    out[id].planned += 1;
    point_of_key.emplace(job.id.key, id);
  }
  for (const StoredRun& r : runs) {  // only this round's jobs: replicates 0 .. n-1 of each point
    auto it = point_of_key.find(r.id.key);
    if (it == point_of_key.end()) continue;
    PointRuns& p = out[it->second];
    p.stored += 1;
    if (const auto j = run_j(r.record, j_kind)) p.j.push_back(*j);
  }
  return out;
}

ModelKind model_of(const std::string& name) { return parse_model_kind(name); }

void add_round(RunnerSummary& total, const RunnerSummary& round) {
  total.already_stored = round.already_stored - total.done_now;  // runs stored before this session
  total.total = round.total;
  total.done_now += round.done_now;
  total.failed.insert(total.failed.end(), round.failed.begin(), round.failed.end());
  total.cancelled = round.cancelled;
}

}  // namespace

ReplicateCounts stored_replicate_counts(const std::vector<StoredRun>& runs) {
  ReplicateCounts out;
  for (const StoredRun& r : runs) {
    int& n = out[{r.id.series, r.id.point, r.id.model}];
    n = std::max(n, r.id.replicate + 1);
  }
  return out;
}

RunnerSummary run_sequential_rounds(const StudyDef& study, Store& store, const RunnerOptions& options,
                                    RunnerSummary summary, const JobRunner& run, std::ostream* log) {
  ReplicateCounts counts;
  std::vector<Job> jobs = expand_jobs(study, counts);
  for (int round = 1; !summary.cancelled && summary.failed.empty(); ++round) {
    const std::map<PointId, PointRuns> points = points_of_round(jobs, store.load(study.name), study.report.j);
    int growing = 0, added = 0;
    for (const auto& [id, p] : points) {
      if (p.stored < p.planned) continue;  // a run is missing (failed elsewhere): no decision on partial data
      const SequentialStep step =
          sequential_step(p.j, p.planned, max_replicates_for(study, model_of(std::get<2>(id))), study.sequential);
      if (step.next > p.planned) ++growing, added += step.next - p.planned;
      counts[id] = step.next;
    }
    if (growing == 0) break;
    if (log)
      *log << fmt::format("sequential round {}: {} of {} points wider than +-{:.3g} % of mean J_{}: {} more runs\n",
                          round, growing, points.size(), 100 * study.sequential.target_halfwidth, study.report.j,
                          added);
    jobs = expand_jobs(study, counts);
    add_round(summary, run(jobs, store, options));
  }
  if (log && !summary.cancelled) {
    for (const auto& [id, p] : points_of_round(jobs, store.load(study.name), study.report.j)) {
      const SequentialStep s =
          sequential_step(p.j, p.planned, max_replicates_for(study, model_of(std::get<2>(id))), study.sequential);
      *log << fmt::format("  {} {} '{}': {} replicates, J_{} +-{:.3g} % ({})\n", std::get<0>(id), std::get<2>(id),
                          p.label, p.planned, study.report.j, 100 * s.relative_halfwidth,
                          s.reached ? "target reached" : p.stored < p.planned ? "runs missing" : "cap reached");
    }
  }
  return summary;
}

}  // namespace gapflow

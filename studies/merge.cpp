#include "studies/merge.hpp"

#include "studies/record_pack.hpp"

#include <fmt/format.h>

#include <map>
#include <set>
#include <stdexcept>

namespace gapflow {

std::string run_difference(const StoredRun& a, const StoredRun& b) {
  if (std::string d = identity_difference(a.id, b.id); !d.empty()) return "identity differs: " + d;
  if (!same_results(a.record, b.record)) return "results differ";
  if (a.code_version != b.code_version)
    return fmt::format("code version differs: {} vs {}", a.code_version, b.code_version);
  return "";
}

namespace {

std::map<std::string, StoredRun> by_key(std::vector<StoredRun> runs) {
  std::map<std::string, StoredRun> out;
  for (StoredRun& r : runs) {
    std::string key = r.id.key;
    out.emplace(std::move(key), std::move(r));
  }
  return out;
}

// Where a run came from, as the output keeps it: the source's own provenance when it has one.
Provenance provenance_of(const StoredRun& run, const std::map<std::string, Provenance>& known,
                         const std::filesystem::path& source) {
  auto it = known.find(run.id.key);
  Provenance p = it != known.end() ? it->second : Provenance{"", "", run.code_version, ""};
  if (p.merged_from.empty()) p.merged_from = source.string();
  return p;
}

}  // namespace

MergeSummary merge_stores(Store& out, const std::vector<std::filesystem::path>& sources) {
  for (const auto& s : sources)
    if (!std::filesystem::is_regular_file(s)) throw std::invalid_argument("merge: no results store at " + s.string());
  MergeSummary summary;
  std::set<std::string> stored = out.keys();  // runs are read back only where a key collides
  std::map<std::string, PlannedJob> plan;
  for (PlannedJob& p : out.plan()) plan.emplace(p.id.key, std::move(p));
  std::map<std::string, bool> has_study_file;
  for (const StudyFileRecord& f : out.study_files()) has_study_file[f.study] = true;

  for (const auto& source : sources) {
    const Store in(source, StoreAccess::read);
    const std::map<std::string, Provenance> known = in.provenance();
    std::vector<StoredRun> batch;
    std::vector<Provenance> batch_provenance;
    for (StoredRun& run : in.load()) {
      if (stored.count(run.id.key)) {
        if (std::string d = run_difference(*out.load_run(run.id.key), run); !d.empty())
          summary.conflicts.push_back({run.id.key, source, d});
        else
          ++summary.identical;
        continue;
      }
      batch_provenance.push_back(provenance_of(run, known, source));
      stored.insert(run.id.key);
      batch.push_back(std::move(run));
    }
    out.import_runs(batch, batch_provenance);  // before the next source, which may collide with these
    summary.added += static_cast<int>(batch.size());
    for (PlannedJob& p : in.plan()) plan.emplace(p.id.key, std::move(p));
    for (const StudyFileRecord& f : in.study_files())
      if (!has_study_file[f.study]) {
        out.record_study_file(f.study, f.source, f.text);
        has_study_file[f.study] = true;
      }
  }

  if (!plan.empty()) {
    std::vector<PlannedJob> all;
    for (auto& [key, p] : plan) {
      if (!stored.count(key)) summary.missing.push_back(p);
      all.push_back(std::move(p));
    }
    out.record_plan(all);
    summary.planned = static_cast<int>(all.size());
  }
  return summary;
}

std::vector<std::string> compare_stores(const Store& a, const Store& b) {
  const std::map<std::string, StoredRun> ra = by_key(a.load()), rb = by_key(b.load());
  std::vector<std::string> out;
  for (const auto& [key, run] : ra) {
    auto it = rb.find(key);
    if (it == rb.end()) {
      out.push_back(fmt::format("{}: only in the first store ({} '{}' {} r{})", key, run.id.series,
                                run.id.point_label, run.id.model, run.id.replicate));
    } else if (std::string d = run_difference(run, it->second); !d.empty()) {
      out.push_back(fmt::format("{}: {}", key, d));
    }
  }
  for (const auto& [key, run] : rb)
    if (!ra.count(key))
      out.push_back(fmt::format("{}: only in the second store ({} '{}' {} r{})", key, run.id.series,
                                run.id.point_label, run.id.model, run.id.replicate));
  return out;
}

}  // namespace gapflow

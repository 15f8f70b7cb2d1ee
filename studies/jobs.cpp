#include "studies/jobs.hpp"

#include "common/geometry.hpp"
#include "common/input_bounds.hpp"
#include "common/random.hpp"
#include "common/text_file.hpp"

#include <fmt/format.h>

#include <map>

namespace gapflow {

std::uint64_t model_key_id(ModelKind kind) {
  // Written out so that reordering ModelKind can never change a job key.
  switch (kind) {
    case ModelKind::box2d: return 2;
    case ModelKind::bullet: return 3;
  }
  return 0;
}

std::string job_key(std::uint64_t scenario_hash, ModelKind kind) {
  return fmt::format("{:016x}", mix_seed(scenario_hash, model_key_id(kind)));
}

double expected_run_cost(const CompiledScenario& scenario, ModelKind kind) {
  const double model_factor = kind == ModelKind::bullet ? 2.5 : 1.0;  // 3D ~62 s vs 2D ~25 s per run (README)
  return model_factor * static_cast<double>(scenario.particles.size()) * scenario.def.run.time_limit_s;
}

namespace {

// One point of a series' grid: the value index on each axis.
struct Point {
  int index = 0;
  std::vector<std::size_t> value_of_axis;
};

// The i-th point of a series' grid.
Point grid_point(const SeriesDef& s, std::size_t i) {
  Point p{static_cast<int>(i), std::vector<std::size_t>(s.axes.size())};
  std::size_t rest = i;
  for (std::size_t k = s.axes.size(); k-- > 0;) {  // last axis varies fastest
    p.value_of_axis[k] = rest % s.axes[k].values.size();
    rest /= s.axes[k].values.size();
  }
  return p;
}

std::vector<Point> grid_points(const SeriesDef& s) {
  std::size_t n = 1;
  for (const SweepAxis& a : s.axes) n *= a.values.size();
  std::vector<Point> out;
  for (std::size_t i = 0; i < n; ++i) out.push_back(grid_point(s, i));
  return out;
}

// Whether a model with [per_model] thin runs this point (the point keeps its index in the full grid).
bool kept_by_thinning(const SeriesDef& s, const Point& p, int thin) {
  for (std::size_t k = 0; k < s.axes.size(); ++k)
    if (!thin_keeps(p.value_of_axis[k], s.axes[k].values.size(), thin)) return false;
  return true;
}

// The point's overrides with their study-file locations, its label and its JSON.
struct PointSpec {
  std::vector<LocatedOverride> overrides;
  std::string label;
  std::string json;
};

PointSpec point_spec(const StudyDef& study, const SeriesDef& s, const Point& p) {
  PointSpec spec;
  spec.overrides = study.set;
  spec.overrides.insert(spec.overrides.end(), s.set.begin(), s.set.end());
  std::string json;
  for (std::size_t k = 0; k < s.axes.size(); ++k) {
    const AxisValue& v = s.axes[k].values[p.value_of_axis[k]];
    const std::string assignment = s.axes[k].key + "=" + v.toml;
    spec.overrides.push_back({assignment, v.where});
    spec.label += (k ? ", " : "") + assignment;
    json += fmt::format("{}\"{}\":{}", k ? "," : "", s.axes[k].key, v.json);
  }
  spec.json = "{" + json + "}";
  return spec;
}

std::string read_scenario_text(const SeriesDef& s) {
  try {
    return read_input_file(s.scenario, "scenario file");  // bounded: a series may name /dev/zero
  } catch (const FileError& e) {
    throw ScenarioError(s.scenario_where, "series.scenario", "\"" + s.scenario.string() + "\"",
                        fmt::format("{} (relative to the study file) [series '{}']", e.reason(), s.label));
  }
}

// Re-throw a scenario error at the study-file location of the override that
// caused it (the loader calls override N "--set:N"), naming series and point.
[[noreturn]] void rethrow_in_study(const ScenarioError& e, const std::vector<LocatedOverride>& overrides,
                                   const SeriesDef& s, const PointSpec& spec) {
  SourceLocation at = e.where();
  if (at.source == "--set" && at.line >= 1 && static_cast<std::size_t>(at.line) <= overrides.size())
    at = overrides[static_cast<std::size_t>(at.line) - 1].where;
  const std::string context = spec.label.empty() ? fmt::format("series '{}'", s.label)
                                                 : fmt::format("series '{}', point {}", s.label, spec.label);
  throw ScenarioError(at, e.key(), e.value(), fmt::format("{} [{}]", e.allowed(), context));
}

}  // namespace

CompiledScenario compile_job(const Job& job) {
  LoadedScenario loaded = load_scenario(job.scenario, job.overrides);
  try {
    return compile_scenario(loaded.def);
  } catch (const ScenarioInvalid& e) {
    throw locate(e, loaded);
  }
}

namespace {

// One job: its scenario resolved, validated and hashed.
Job make_job(const StudyDef& study, const SeriesDef& s, const std::string& scenario_text, const Point& p,
             const PointSpec& spec, ModelKind model, int replicate) {
  std::vector<LocatedOverride> overrides = spec.overrides;
  if (auto plan = study.per_model.find(model); plan != study.per_model.end())
    overrides.insert(overrides.end(), plan->second.set.begin(), plan->second.set.end());
  const SourceLocation seed_at{study.file.string(), 0, 0};
  overrides.push_back({fmt::format("run.seed={}", study.seed), seed_at});
  overrides.push_back({fmt::format("run.replicate={}", replicate), seed_at});
  Job job;
  for (const LocatedOverride& o : overrides) job.overrides.push_back(o.text);
  try {
    LoadedScenario loaded = parse_scenario(scenario_text, s.scenario.string(), job.overrides);
    try {
      const CompiledScenario sc = compile_scenario(loaded.def);
      check_model_supports(sc, model);
      job.id.scenario_hash = sc.scenario_hash;
      job.id.run_seed = sc.run_seed;
      job.expected_cost = expected_run_cost(sc, model);
      job.time_limit_s = sc.def.run.time_limit_s;
    } catch (const ScenarioInvalid& e) {
      throw locate(e, loaded);
    }
  } catch (const ScenarioError& e) {
    rethrow_in_study(e, overrides, s, spec);
  }
  job.model = model;
  job.scenario = s.scenario;
  job.id.key = job_key(job.id.scenario_hash, model);
  job.id.study = study.name;
  job.id.series = s.label;
  job.id.point = p.index;
  job.id.point_label = spec.label;
  job.id.axes_json = spec.json;
  job.id.model = to_string(model);
  job.id.replicate = replicate;
  job.id.base_seed = study.seed;
  return job;
}

// Two jobs with one key would be stored as one: name both points.
void check_unique(std::map<std::string, std::size_t>& first_of_key, const std::vector<Job>& jobs, const Job& job,
                  const PointSpec& spec, const std::string& study_file) {
  auto [it, fresh] = first_of_key.emplace(job.id.key, jobs.size());
  if (fresh) return;
  const JobIdentity& other = jobs[it->second].id;
  throw ScenarioError(spec.overrides.empty() ? SourceLocation{study_file, 0, 0} : spec.overrides.back().where,
                      "series", "\"" + job.id.series + "\"",
                      fmt::format("point '{}' resolves to the same scenario as series '{}' point '{}' (job key {}): "
                                  "remove the duplicate",
                                  job.id.point_label, other.series, other.point_label, job.id.key));
}

}  // namespace

std::vector<Job> point_jobs(const StudyDef& study, const SeriesDef& series, int point, ModelKind model, int first,
                            int last) {
  const Point p = grid_point(series, static_cast<std::size_t>(point));
  const std::string text = read_scenario_text(series);
  const PointSpec spec = point_spec(study, series, p);
  std::vector<Job> out;
  for (int r = first; r < last; ++r) out.push_back(make_job(study, series, text, p, spec, model, r));
  return out;
}

double count_jobs(const StudyDef& study) {
  double total = 0;  // a double cannot overflow here: every factor is bounded by the loader
  for (const SeriesDef& s : study.series)
    for (ModelKind model : study.models) {
      double points = 1;
      for (const SweepAxis& a : s.axes) {
        const std::size_t n = a.values.size(), thin = static_cast<std::size_t>(std::max(1, thin_for(study, model)));
        points *= static_cast<double>((n + thin - 1) / thin + ((n - 1) % thin != 0 ? 1 : 0));
      }
      total += points * max_replicates_for(study, model);
    }
  if (study.confirm.enabled) total += static_cast<double>(study.confirm.top) * study.confirm.replicates;
  return total;
}

std::vector<Job> expand_jobs(const StudyDef& study) { return expand_jobs(study, {}); }

std::vector<Job> expand_jobs(const StudyDef& study, const ReplicateCounts& counts) {
  // Checked before anything is allocated: a billion replicates must fail at once, not after minutes.
  if (const double n = count_jobs(study); n > static_cast<double>(kMaxStudyJobs))
    throw ScenarioError({study.file.string(), 0, 0}, "", "",
                        fmt::format("the study expands to {:.6g} jobs (series x points x models x replicates, "
                                    "plus [confirm] top x replicates); at most {} are allowed: split it or thin "
                                    "its axes",
                                    n, kMaxStudyJobs));
  std::vector<Job> jobs;
  std::map<std::string, std::size_t> first_of_key;
  for (const SeriesDef& s : study.series) {
    const std::string text = read_scenario_text(s);  // once per series, not once per job
    for (const Point& p : grid_points(s)) {
      const PointSpec spec = point_spec(study, s, p);
      for (ModelKind model : study.models) {
        if (!kept_by_thinning(s, p, thin_for(study, model))) continue;
        const auto raised = counts.find({s.label, p.index, to_string(model)});
        const int n = raised != counts.end() ? raised->second : replicates_for(study, model);
        for (int r = 0; r < n; ++r) {
          Job job = make_job(study, s, text, p, spec, model, r);
          check_unique(first_of_key, jobs, job, spec, study.file.string());
          jobs.push_back(std::move(job));
        }
      }
    }
  }
  return jobs;
}

}  // namespace gapflow

#include "calibrate/evaluator.hpp"

#include "calibrate/effect_catalogue.hpp"

#include "common/geometry.hpp"
#include "common/statistics.hpp"
#include "common/toml_strict.hpp"
#include "common/units.hpp"
#include "studies/jobs.hpp"

#include <fmt/format.h>

#include <cmath>
#include <map>
#include <mutex>
#include <set>

namespace gapflow {

std::string ParameterSet::label() const {
  if (values.empty()) return "template";
  std::string s;
  for (const auto& [k, v] : values) s += (s.empty() ? "" : ", ") + k + "=" + number_text(v);
  return s;
}

std::vector<std::string> ParameterSet::overrides() const {
  std::vector<std::string> out;
  for (const auto& [k, v] : values) out.push_back(k + "=" + number_text(v));
  return out;
}

ParameterSet ParameterSet::with(const std::string& key, double value) const {
  ParameterSet p = *this;
  for (auto& [k, v] : p.values)
    if (k == key) {
      v = value;
      return p;
    }
  p.values.emplace_back(key, value);
  return p;
}

double ParameterSet::get(const std::string& key, double fallback) const {
  for (const auto& [k, v] : values)
    if (k == key) return v;
  return fallback;
}

namespace {

// A slimmed store (scripts/slim_store.py) keeps a run's summary without its crossing times: an
// observable made of them would read such runs as runs that passed nothing.
void require_crossings(const RunRecord& r) {
  if (!crossings_stored(r))
    throw std::runtime_error("a stored run has no crossing times (a store slimmed by scripts/slim_store.py); "
                             "calibrate with the full store");
}

// One run's value of a per-run observable: a rate (particles/s), the front's arrival
// (s), or the mean or spread of where its particles crossed the gap line (mm from the
// gap's centre; plane frame, +x across). Missing when the run does not define it.
std::optional<double> per_run_value(ObservableKind kind, const RunRecord& r) {
  switch (kind) {
    case ObservableKind::j_paper: return r.j_paper;
    case ObservableKind::j_mid: return r.j_mid;
    case ObservableKind::j_flowing: return r.j_flowing;
    case ObservableKind::j_star: return r.j_paper_star();
    case ObservableKind::front_arrival:
      require_crossings(r);
      if (r.crossings.empty()) return std::nullopt;
      return r.crossings.front().t;  // sorted by time (GapMonitor::finish)
    case ObservableKind::exit_offset:
    case ObservableKind::exit_spread: {
      require_crossings(r);
      std::vector<double> x_mm;
      for (const Crossing& c : r.crossings) x_mm.push_back(c.x * 1e3);
      const Summary s = summarize(x_mm);
      if (s.n < (kind == ObservableKind::exit_offset ? 1u : 2u)) return std::nullopt;
      return kind == ObservableKind::exit_offset ? s.mean : s.sd;
    }
    default: return std::nullopt;  // pooled over runs (avalanches, clog share): observe()
  }
}

// A mean over replicates of a per-run quantity; se from their spread.
PointObservable mean_observable(const std::vector<double>& per_run, FitScale scale) {
  PointObservable o;
  for (double v : per_run) o.replicate_fit.push_back(v > 0 || scale == FitScale::linear ? to_fit_scale(scale, v) : kNaN);
  const Summary s = summarize(per_run);
  o.value = s.mean;
  o.valid = s.n == per_run.size() && s.n >= 2 && (scale == FitScale::linear || s.mean > 0);
  if (!o.valid) return o;
  o.fit = to_fit_scale(scale, s.mean);
  o.se_fit = scale == FitScale::log ? s.se() / s.mean : s.se();  // delta method on the log
  return o;
}

// <s>: censoring-aware mean over the pooled avalanches (first ones dropped), with
// the chi-square interval's half-width as ~2 se. Per replicate for CRN differences.
PointObservable avalanche_observable(ObservableKind kind, FitScale scale, const std::vector<RunRecord>& runs) {
  auto sizes_of = [](const std::vector<const RunRecord*>& rs) {
    std::vector<double> v;
    std::vector<bool> c;
    for (const RunRecord* r : rs)
      for (const Avalanche& a : r->avalanches)
        if (!a.first) v.push_back(a.size), c.push_back(a.censored);
    return censored_exponential_mean(v, c);
  };
  auto transform = [&](double s) { return kind == ObservableKind::ln_s_plus_1 ? std::log(s + 1) : s; };
  std::vector<const RunRecord*> all;
  for (const RunRecord& r : runs) all.push_back(&r);
  const CensoredMean m = sizes_of(all);
  PointObservable o;
  for (const RunRecord& r : runs) {
    const CensoredMean one = sizes_of({&r});
    o.replicate_fit.push_back(one.mean == one.mean ? to_fit_scale(scale, transform(one.mean)) : kNaN);
  }
  o.valid = m.mean == m.mean && m.ci95.valid();
  if (!o.valid) return o;
  const double se_s = (m.ci95.hi - m.ci95.lo) / (2 * 1.959963984540054);
  o.value = transform(m.mean);
  o.fit = to_fit_scale(scale, o.value);
  const double se_value = kind == ObservableKind::ln_s_plus_1 ? se_s / (m.mean + 1) : se_s;
  o.se_fit = scale == FitScale::log ? se_value / o.value : se_value;
  return o;
}

}  // namespace

PointObservable observe(ObservableKind kind, FitScale scale, const std::vector<RunRecord>& runs) {
  switch (kind) {
    case ObservableKind::mean_avalanche:
    case ObservableKind::ln_s_plus_1: return avalanche_observable(kind, scale, runs);
    case ObservableKind::clog_share: {
      std::vector<double> clogged;
      for (const RunRecord& r : runs) clogged.push_back(r.clogs.empty() ? 0.0 : 1.0);
      PointObservable o = mean_observable(clogged, FitScale::linear);
      // A share of 0 or 1 over n runs still has an uncertainty: the rule of three's ~1/(2n).
      if (o.valid) o.se_fit = std::max(o.se_fit, 0.5 / static_cast<double>(runs.size()));
      return o;
    }
    default: {
      std::vector<double> rates;
      for (const RunRecord& r : runs) rates.push_back(per_run_value(kind, r).value_or(kNaN));
      std::vector<double> defined;
      for (double v : rates)
        if (v == v) defined.push_back(v);
      PointObservable o = mean_observable(defined, scale);
      o.valid = o.valid && defined.size() == rates.size();
      o.replicate_fit.clear();
      for (double v : rates)
        o.replicate_fit.push_back(v == v && (v > 0 || scale == FitScale::linear) ? to_fit_scale(scale, v) : kNaN);
      return o;
    }
  }
}

Evaluator::Evaluator(const DataFile& data, Store& store, EvaluatorOptions options)
    : data_(data), store_(store), options_(options) {}

std::vector<Prediction> Evaluator::evaluate(const std::vector<ParameterSet>& sets, std::uint64_t seed,
                                            int replicates, const std::vector<bool>& only) {
  if (!only.empty() && only.size() != data_.points.size())
    throw std::invalid_argument("evaluate: the points mask must have one flag per design point");
  const auto wanted = [&](std::size_t i) { return only.empty() || only[i]; };
  // Jobs: set x wanted point x replicate, each with its own key.
  std::vector<Job> jobs;
  std::vector<ScenarioDef> point_defs;
  for (std::size_t i = 0; i < data_.points.size(); ++i) point_defs.push_back(data_.point_scenario(i).def);
  for (std::size_t s = 0; s < sets.size(); ++s)
    for (std::size_t i = 0; i < data_.points.size(); ++i)
      for (int r = 0; r < (wanted(i) ? replicates : 0); ++r) {
        Job job;
        job.model = options_.model;
        job.scenario = data_.scenario;
        job.overrides = data_.point_overrides(i);
        for (const auto& [key, value] : sets[s].values)
          if (key_applies_to(key, point_defs[i])) job.overrides.push_back(key + "=" + number_text(value));
        job.overrides.push_back(fmt::format("run.seed={}", seed));
        job.overrides.push_back(fmt::format("run.replicate={}", r));
        const CompiledScenario sc = compile_job(job);
        check_model_supports(sc, options_.model);  // e.g. a free friction_base below the 2D slip limit
        job.id.scenario_hash = sc.scenario_hash;
        job.id.run_seed = sc.run_seed;
        job.id.key = job_key(sc.scenario_hash, options_.model);
        job.id.study = "calibrate:" + data_.name;
        job.id.series = sets[s].label();
        job.id.point = static_cast<int>(i);
        job.id.point_label = data_.point_label(i);
        job.id.axes_json = "{}";
        job.id.model = to_string(options_.model);
        job.id.replicate = r;
        job.id.base_seed = seed;
        jobs.push_back(std::move(job));
      }
  // Run what is missing; keep the records of this call in memory.
  std::map<std::string, RunRecord> fresh;
  std::set<std::string> counted;  // a run shared by points (several observables) is counted once
  std::mutex fresh_mutex;
  RunnerOptions ro;
  ro.workers = options_.workers;
  ro.cancel = options_.cancel;
  ro.progress = options_.progress;
  ro.tty = options_.tty;
  ro.run = [&](const Job& job, const std::atomic<bool>* cancel) {
    RunRecord rec = run_model(compile_job(job), job.model, nullptr, cancel);
    std::lock_guard lock(fresh_mutex);
    fresh[job.id.key] = rec;
    return rec;
  };
  // A set may repeat (a fit that added nothing is re-scored with its baseline): run each key once.
  std::vector<Job> unique;
  std::set<std::string> seen;
  for (const Job& j : jobs)
    if (seen.insert(j.id.key).second) unique.push_back(j);
  const RunnerSummary summary = options_.runner ? options_.runner(unique, store_, ro) : run_jobs(unique, store_, ro);
  if (summary.cancelled) throw RunCancelled();
  if (!summary.failed.empty())
    throw std::runtime_error(fmt::format("{} model runs failed; first: {} ({})", summary.failed.size(),
                                         summary.failed.front().id.point_label, summary.failed.front().error));
  simulated_ += summary.done_now;
  reused_ += summary.already_stored;

  std::vector<Prediction> out(sets.size());
  std::size_t j = 0;
  for (std::size_t s = 0; s < sets.size(); ++s) {
    Prediction& p = out[s];
    for (std::size_t i = 0; i < data_.points.size(); ++i) {
      if (!wanted(i)) {
        p.value.push_back(kNaN), p.fit.push_back(kNaN), p.se_fit.push_back(kNaN);
        p.replicate_fit.emplace_back(), p.valid.push_back(false);
        continue;
      }
      std::vector<RunRecord> runs;
      for (int r = 0; r < replicates; ++r, ++j) {
        auto it = fresh.find(jobs[j].id.key);
        if (it != fresh.end()) {
          runs.push_back(it->second);
        } else {
          std::optional<StoredRun> stored = store_.load_run(jobs[j].id.key);
          if (!stored) throw std::runtime_error("run " + jobs[j].id.key + " is missing from the store");
          runs.push_back(std::move(stored->record));
        }
        if (counted.insert(jobs[j].id.key).second) run_seconds_ += runs.back().wall_time_s;
      }
      const DataPoint& point = data_.points[i];
      const PointObservable o = observe(point.observable, point.scale, runs);
      p.value.push_back(o.value);
      p.fit.push_back(o.fit);
      p.se_fit.push_back(o.se_fit);
      p.replicate_fit.push_back(o.replicate_fit);
      p.valid.push_back(o.valid);
    }
  }
  return out;
}

}  // namespace gapflow

// A study expanded into jobs: one job = (series, point, model, replicate).
//
// The job key identifies a job on any machine: 16 hex digits of
// mix_seed(scenario_hash(resolved scenario), model id), where the resolved
// scenario includes run.seed and run.replicate. The same job list can therefore
// be farmed out (Slurm array index -> job) and merged by key.
#pragma once

#include "studies/study.hpp"

#include <cstdint>
#include <filesystem>
#include <map>
#include <string>
#include <tuple>
#include <vector>

namespace gapflow {

// What a stored run says about where it came from (the `runs` table's identity columns).
struct JobIdentity {
  std::string key;          // 16 hex digits
  std::string study;
  std::string series;
  int point = 0;            // index in the series' grid (first axis slowest)
  std::string point_label;  // "obstruction.distance_mm=70, bottleneck.gap_mm=33"; "" without axes
  std::string axes_json;    // {"obstruction.distance_mm":70}
  std::string model;        // "2d" | "3d"
  int replicate = 0;
  std::uint64_t base_seed = 0;
  std::uint64_t run_seed = 0;
  std::uint64_t scenario_hash = 0;
};

struct Job {
  JobIdentity id;
  ModelKind model = ModelKind::box2d;
  std::filesystem::path scenario;       // the series' scenario file
  std::vector<std::string> overrides;   // study set, series set, axis values, run.seed, run.replicate
  double expected_cost = 0;             // relative cost of the run (expected_run_cost); 0 = unknown
  double time_limit_s = 0;              // s, the compiled scenario's run.time_limit_s (a screen's horizon)
};

// What a run is expected to cost, in 2D particle-seconds: particles x run.time_limit_s, times ~2.5 for the
// 3D model (measured per run: README "Studies"). A bound, not a forecast (a run may end early), but it
// ranks jobs the way their wall time does, which is what balancing shards needs (studies/shard.hpp).
double expected_run_cost(const CompiledScenario& scenario, ModelKind kind);

// Stable numeric id of a model in job keys (never the enum's position).
std::uint64_t model_key_id(ModelKind kind);
std::string job_key(std::uint64_t scenario_hash, ModelKind kind);

// Every job of the study, in order series, point, model, replicate. Each job's
// scenario is loaded and compiled here, before anything runs; a bad one throws
// ScenarioError located in the study file when the culprit is one of its
// overrides (else in the scenario file), naming the series and the point.
std::vector<Job> expand_jobs(const StudyDef& study);
// The same with some points' replicate counts raised (sequential replication, studies/sequential.hpp):
// (series label, point index, model "2d"|"3d") -> replicates 0 .. n-1; points not listed run the study's.
using ReplicateCounts = std::map<std::tuple<std::string, int, std::string>, int>;
std::vector<Job> expand_jobs(const StudyDef& study, const ReplicateCounts& counts);

// The jobs of one point of one series for replicates [first, last), with expand_jobs' keys:
// what an adaptive study adds round by round (studies/screen.cpp). Throws like expand_jobs.
std::vector<Job> point_jobs(const StudyDef& study, const SeriesDef& series, int point, ModelKind model, int first,
                            int last);

// How many jobs expand_jobs would make (with the [confirm] stage's), computed without
// making them; expand_jobs refuses more than kMaxStudyJobs (common/input_bounds.hpp).
double count_jobs(const StudyDef& study);

// Load and compile a job's scenario (the runner calls this again in its worker).
CompiledScenario compile_job(const Job& job);

}  // namespace gapflow

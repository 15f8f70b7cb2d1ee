// Study description: which scenarios, which parameter sweeps, which models and
// how many replicates. Loaded strictly from TOML (toml++), like a scenario:
// unknown keys, wrong types and bad values are ScenarioErrors that say
// file:line:column, the key, the value and what is allowed.
//
//   [study]     name, description, replicates, models, seed, set,
//               replicates_target_halfwidth, replicates_max, replicates_batch (sequential replication)
//   [[series]]  label, scenario (relative to the study file), set
//     [[series.sweep]]  key + values, or key + from/to/step (inclusive)
//   [per_model.2d] / [per_model.3d]  replicates, thin, set  (a model's own budget: the 3D
//               model costs ~3x the 2D one per run, so it may run fewer replicates on a
//               coarser grid; its points keep their indices in the full grid; set: overrides
//               for that model's runs only, e.g. a 2D reduced-model effect that leaves the
//               3D runs, and their keys in a store, as they were)
//   [quick]     replicates, models, thin  (what --quick changes)
//   [confirm]   model, top, replicates, rank_by, set  (screen -> confirm)
//   [report]    kind (string or list), baseline, j, pairing
//   [screen]    a racing screen over shape x size x D x W instead of [[series]] (studies/screen_def.hpp)
#pragma once

#include "models/registry.hpp"
#include "common/scenario_loader.hpp"
#include "studies/screen_def.hpp"

#include <cstdint>
#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace gapflow {

// One scenario override ("key=value") and where the study file wrote it.
struct LocatedOverride {
  std::string text;
  SourceLocation where;
};

// One value of a sweep axis.
struct AxisValue {
  std::string toml;     // literal as an override value: 70, 80.5, "cylinder", true
  std::string json;     // literal for axes_json: same, but strings in JSON quoting
  SourceLocation where; // of the value (or of `from` for a from/to/step axis)
};

// [[series.sweep]]: one scenario key and the values it takes.
struct SweepAxis {
  std::string key;  // dotted scenario key, e.g. obstruction.distance_mm
  std::vector<AxisValue> values;
};

// [[series]]: one scenario file, its own overrides and a grid of sweep axes.
struct SeriesDef {
  std::string label;
  std::filesystem::path scenario;  // resolved against the study file's folder
  SourceLocation scenario_where;   // of `scenario = ...` in the study file
  std::vector<LocatedOverride> set;
  std::vector<SweepAxis> axes;     // grid = cartesian product; first axis varies slowest
};

// [per_model.<model>]: one model's replicates and grid thinning, instead of the study's.
struct ModelPlan {
  std::optional<int> replicates;  // per point (default: [study] replicates)
  int thin = 1;                   // run every thin-th value of each axis (always the first and the last)
  std::vector<LocatedOverride> set;  // this model's runs only, after the study's and series' (e.g. a 2D-only effect)
};

// [quick]: a cheaper version of the study for a first look.
struct QuickDef {
  bool present = false;           // the file has a [quick] table (without one, --quick is an error)
  std::optional<int> replicates;
  std::optional<std::vector<ModelKind>> models;
  int thin = 1;  // keep every thin-th value of each axis (and always the first and the last)
};

// [confirm]: screen -> confirm. After the study's jobs (the screen, usually
// 2D), the `top` points with the highest mean J are run again with `model`.
struct ConfirmDef {
  bool enabled = false;
  ModelKind model = ModelKind::bullet;
  int top = 3;                     // points confirmed (over all series)
  int replicates = 10;             // per confirmed point
  std::string rank_by = "paper";   // J used for ranking: paper | flowing | mid
  std::vector<LocatedOverride> set; // overrides for the confirming runs only, after the study's and series'
};

// [report]: which experiment analyses `gapflow report` runs (studies/report*.cpp).
struct ReportDef {
  std::vector<std::string> kinds;  // flow_vs_gap, flow_vs_distance, clogging, models, screen_confirm
  std::string baseline;            // series label of the no-obstruction reference ("" = none)
  std::string j = "paper";         // J used by the analyses: paper | flowing | mid
  std::string pairing = "unpaired"; // J/J_0: unpaired | paired (by replicate where the sets match; studies/paired.hpp)
};

// [study] replicates_target_halfwidth: sequential replication (studies/sequential.hpp). Each point
// runs `replicates` (the minimum, >= kMinSequentialReplicates), then batches of `batch` more while
// the Student-t 95 % interval of its mean J (the [report] j) is wider than +-target_halfwidth x
// mean, up to max_replicates.
inline constexpr int kMinSequentialReplicates = 10;
struct SequentialDef {
  bool enabled = false;
  double target_halfwidth = 0;  // relative half-width (0.02 = +-2 % of the mean), dimensionless
  int max_replicates = 0;       // cap per point and model (replicates_max)
  int batch = 5;                // replicates added per round to a point still too wide (replicates_batch)
};

struct StudyDef {
  std::filesystem::path file;  // the study file ("" when parsed from text)
  std::string name;
  std::string description;
  int replicates = 20;         // per point and model (the paper repeats each point 20 times)
  std::vector<ModelKind> models{ModelKind::box2d};
  std::uint64_t seed = 1;      // run.seed of every job
  std::vector<LocatedOverride> set;  // overrides for every series
  std::vector<SeriesDef> series;
  std::map<ModelKind, ModelPlan> per_model;
  QuickDef quick;
  ConfirmDef confirm;
  ReportDef report;
  SequentialDef sequential;
  std::optional<ScreenDef> screen;  // [screen]: series made from its grid, run round by round (studies/screen.hpp)
};

// Load and validate a study file. Scenario files and keys are checked later,
// job by job, by expand_jobs() (jobs.hpp).
StudyDef load_study(const std::filesystem::path& file);
// Same, from text (tests). Scenario paths are resolved against base_dir.
StudyDef parse_study(std::string_view text, std::string_view source_name, const std::filesystem::path& base_dir);

// The study as `--quick` runs it: [quick] replicates and models, axes thinned.
StudyDef apply_quick(StudyDef study);

// Every thin-th element of an axis, always keeping the first and the last.
std::vector<AxisValue> thin_values(const std::vector<AxisValue>& values, int thin);
// Whether thin_values keeps the i-th of n values.
bool thin_keeps(std::size_t i, std::size_t n, int thin);

// The replicates and thinning `model` runs with (its [per_model] entry, else the study's).
int replicates_for(const StudyDef& study, ModelKind model);
int thin_for(const StudyDef& study, ModelKind model);
// The most replicates `model` may run per point: replicates_for, or the sequential cap when larger.
int max_replicates_for(const StudyDef& study, ModelKind model);

}  // namespace gapflow

// Strict study loader (toml++). Each table is read through a StrictTable that
// knows its allowed keys: an unknown key (usually a typo) is reported first,
// before any "missing key" it may have caused, and reading a key that is not
// in the list is a programming error, so the list cannot drift from the reader.
#include "studies/study.hpp"

#include "common/input_bounds.hpp"
#include "common/text_file.hpp"
#include "common/toml_parse.hpp"
#include "common/toml_strict.hpp"
#include "studies/analysis.hpp"
#include "studies/screen_loader.hpp"

#include <fmt/format.h>
#include <toml++/toml.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <set>
#include <sstream>

namespace gapflow {

namespace {

// The keys each table allows.
const std::vector<std::string> kRootKeys{"study", "series", "per_model", "quick", "confirm", "report", "screen"};
const std::vector<std::string> kStudyKeys{"name",       "description", "replicates",
                                          "models",     "seed",        "set",
                                          "replicates_target_halfwidth", "replicates_max", "replicates_batch"};
const std::vector<std::string> kSeriesKeys{"label", "scenario", "set", "sweep"};
const std::vector<std::string> kSweepKeys{"key", "values", "from", "to", "step"};
const std::vector<std::string> kQuickKeys{"replicates", "models", "thin"};
const std::vector<std::string> kPlanKeys{"replicates", "thin", "set"};
const std::vector<std::string> kModelNames{"2d", "3d"};
const std::vector<std::string> kConfirmKeys{"model", "top", "replicates", "rank_by", "set"};
const std::vector<std::string> kReportKeys{"kind", "baseline", "j", "fit_w_min", "fit_w_max", "pairing"};
const std::vector<std::string>& kJKinds = jkind_option_names();
const std::vector<std::string> kReportKinds{"flow_vs_gap", "flow_vs_distance", "clogging", "models", "screen_confirm"};

// run.seed and run.replicate belong to the job ([study] seed, replicates): an
// override of them would be silently replaced and several points would collapse.
bool reserved_key(std::string_view key) {
  auto trimmed = key.substr(0, key.find_last_not_of(" \t") + 1);
  trimmed.remove_prefix(std::min(trimmed.find_first_not_of(" \t"), trimmed.size()));
  return trimmed == "run.seed" || trimmed == "run.replicate";
}
constexpr const char* kReserved = "run.seed and run.replicate are set per job: use [study] seed and replicates";

std::vector<ModelKind> read_models(StrictTable& t) {
  const toml::array* a = t.array("models", "model names");
  if (!a) return {ModelKind::box2d};
  const char* allowed = "must be a non-empty array of distinct models, each \"2d\" or \"3d\"";
  std::vector<ModelKind> out;
  for (const toml::node& n : *a) {
    if (!n.is_string() || (n.as_string()->get() != "2d" && n.as_string()->get() != "3d"))
      throw ScenarioError(t.at(n), t.dotted("models"), toml_text(n), allowed);
    ModelKind k = parse_model_kind(n.as_string()->get());
    if (std::find(out.begin(), out.end(), k) != out.end())
      throw ScenarioError(t.at(n), t.dotted("models"), toml_text(n), allowed);
    out.push_back(k);
  }
  if (out.empty()) t.fail("models", *t.get("models"), allowed);
  return out;
}

std::vector<LocatedOverride> read_set(StrictTable& t) {
  std::vector<LocatedOverride> out;
  const toml::array* a = t.array("set", "\"key=value\" strings");
  if (!a) return out;
  for (const toml::node& n : *a) {
    if (!n.is_string() || n.as_string()->get().find('=') == std::string::npos)
      throw ScenarioError(t.at(n), t.dotted("set"), toml_text(n),
                          "each entry must be a \"key=value\" string, e.g. \"run.time_limit_s=300\"");
    const std::string& text = n.as_string()->get();
    if (reserved_key(std::string_view(text).substr(0, text.find('='))))
      throw ScenarioError(t.at(n), t.dotted("set"), toml_text(n), kReserved);
    out.push_back({text, t.at(n)});
  }
  return out;
}

AxisValue axis_value(const toml::node& n, SourceLocation where) { return {toml_text(n), json_text(n), where}; }

// from/to/step, inclusive. Integers stay integers (counts); other values are
// rounded to 12 significant digits so that 0.1 + 2 * 0.1 reads "0.3".
std::vector<AxisValue> range_values(StrictTable& t, const toml::node& from, const toml::node& to,
                                    const toml::node& step) {
  auto finite = [&](const char* key, const toml::node& n) {
    const std::optional<double> v = number_value(n);
    if (!v || !std::isfinite(*v)) t.fail(key, n, "must be a finite number");
    return *v;
  };
  const double lo = finite("from", from), hi = finite("to", to), dv = finite("step", step);
  if (dv <= 0) t.fail("step", step, "must be a finite number > 0");
  if (hi < lo) t.fail("to", to, fmt::format("must be >= from ({})", toml_text(from)));
  const double steps = std::floor((hi - lo) / dv + 1e-9);
  if (!(steps < kMaxAxisValues))
    t.fail("step", step, fmt::format("gives more than {} values from {} to {}", kMaxAxisValues, toml_text(from),
                                     toml_text(to)));
  const bool integral = from.is_integer() && to.is_integer() && step.is_integer();
  std::vector<AxisValue> out;
  for (int i = 0; i <= static_cast<int>(steps); ++i) {
    if (integral) {
      out.push_back(axis_value(toml::value<std::int64_t>(from.as_integer()->get() + i * step.as_integer()->get()),
                               t.at(from)));
    } else {
      double v = std::stod(fmt::format("{:.12g}", lo + i * dv));
      out.push_back(axis_value(toml::value<double>(v), t.at(from)));
    }
  }
  return out;
}

SweepAxis read_axis(StrictTable t) {
  SweepAxis axis;
  auto key = t.text("key", true);
  if (!key) t.missing("key", "required: a scenario key, e.g. \"obstruction.distance_mm\"");
  axis.key = *key;
  if (reserved_key(axis.key)) t.fail("key", *t.get("key"), kReserved);
  const toml::array* values = t.array("values", "numbers, strings or booleans");
  const toml::node *from = t.get("from"), *to = t.get("to"), *step = t.get("step");
  const bool ranged = from || to || step;
  const char* either = "give either values = [...] or from, to and step";
  if (values && ranged) t.fail("values", *t.get("values"), either);
  if (ranged) {
    if (!from) t.missing("from", either);
    if (!to) t.missing("to", either);
    if (!step) t.missing("step", either);
    axis.values = range_values(t, *from, *to, *step);
  } else {
    if (!values) t.missing("values", either);
    if (values->empty() || values->size() > static_cast<std::size_t>(kMaxAxisValues))
      t.fail("values", *values, fmt::format("must hold 1 to {} values", kMaxAxisValues));
    for (const toml::node& n : *values) {
      if (!n.is_number() && !n.is_string() && !n.is_boolean())
        throw ScenarioError(t.at(n), t.dotted("values"), toml_text(n), "each value must be a number, string or boolean");
      axis.values.push_back(axis_value(n, t.at(n)));
    }
  }
  return axis;
}

// Array-of-tables entries, or an error when the key is not one.
std::vector<const toml::table*> table_array(StrictTable& t, std::string_view key, const char* example) {
  std::vector<const toml::table*> out;
  const toml::node* n = t.get(key);
  if (!n) return out;
  if (!n->is_array_of_tables()) t.fail(key, *n, fmt::format("must be an array of tables ({})", example));
  for (const toml::node& e : *n->as_array()) out.push_back(e.as_table());
  return out;
}

SeriesDef read_series(StrictTable t, const std::string& source, const std::filesystem::path& base_dir) {
  SeriesDef s;
  auto label = t.text("label", true);
  if (!label) t.missing("label", "required: a non-empty string, unique in the study");
  s.label = *label;
  auto scenario = t.text("scenario", true);
  if (!scenario) t.missing("scenario", "required: a scenario file, relative to the study file");
  s.scenario = base_dir / *scenario;
  s.scenario_where = t.at(*t.get("scenario"));
  s.set = read_set(t);
  std::set<std::string> keys;
  for (const toml::table* a : table_array(t, "sweep", "[[series.sweep]]")) {
    SweepAxis axis = read_axis(StrictTable(a, "series.sweep", source, kSweepKeys));
    if (!keys.insert(axis.key).second)
      throw ScenarioError(location_of(source, *a->get("key")), "series.sweep.key", "\"" + axis.key + "\"",
                          "each key may be swept once per series");
    s.axes.push_back(std::move(axis));
  }
  return s;
}

QuickDef read_quick(StrictTable t) {
  QuickDef q;
  q.present = true;
  if (!t.get("replicates") && !t.get("models") && !t.get("thin"))
    t.missing("replicates", "[quick] must set replicates, models or thin: an empty one is no cheaper study");
  if (auto r = t.integer("replicates", 1, kMaxReplicates)) q.replicates = static_cast<int>(*r);
  if (t.get("models")) q.models = read_models(t);
  if (auto k = t.integer("thin", 1, kMaxAxisValues)) q.thin = static_cast<int>(*k);
  return q;
}

ModelPlan read_plan(StrictTable t) {
  ModelPlan m;
  if (auto r = t.integer("replicates", 1, kMaxReplicates)) m.replicates = static_cast<int>(*r);
  if (auto k = t.integer("thin", 1, kMaxAxisValues)) m.thin = static_cast<int>(*k);
  m.set = read_set(t);
  return m;
}

// A model's own minimum under sequential replication: within [kMinSequentialReplicates, replicates_max].
void check_sequential_plan(const StudyDef& d, const ModelPlan& m, StrictTable t) {
  if (!d.sequential.enabled || !m.replicates) return;
  if (*m.replicates < kMinSequentialReplicates || *m.replicates > d.sequential.max_replicates)
    t.fail("replicates", *t.get("replicates"),
           fmt::format("with [study] replicates_target_halfwidth, must be >= {} (the minimum before the first look) "
                       "and <= replicates_max ({})",
                       kMinSequentialReplicates, d.sequential.max_replicates));
}

std::string one_of(StrictTable& t, std::string_view key, const std::vector<std::string>& allowed,
                   const std::string& fallback) {
  auto v = t.text(key);
  if (!v) return fallback;
  if (std::find(allowed.begin(), allowed.end(), *v) == allowed.end()) {
    std::string list;
    for (const auto& a : allowed) list += (list.empty() ? "" : ", ") + a;
    t.fail(key, *t.get(key), "one of: " + list);
  }
  return *v;
}

ConfirmDef read_confirm(StrictTable t) {
  ConfirmDef c;
  c.enabled = true;
  c.model = parse_model_kind(one_of(t, "model", {"2d", "3d"}, "3d"));
  if (auto k = t.integer("top", 1, kMaxStudyJobs)) c.top = static_cast<int>(*k);
  if (auto r = t.integer("replicates", 1, kMaxReplicates)) c.replicates = static_cast<int>(*r);
  c.rank_by = one_of(t, "rank_by", kJKinds, c.rank_by);
  c.set = read_set(t);
  return c;
}

ReportDef read_report(StrictTable t) {
  ReportDef r;
  if (const toml::node* n = t.get("kind"); n && n->is_string()) {
    r.kinds.push_back(one_of(t, "kind", kReportKinds, ""));
  } else if (const toml::array* a = t.array("kind", "analysis names")) {
    for (const toml::node& k : *a) {
      if (!k.is_string() || std::find(kReportKinds.begin(), kReportKinds.end(), k.as_string()->get()) ==
                                kReportKinds.end())
        throw ScenarioError(t.at(k), t.dotted("kind"), toml_text(k),
                            "each one of: flow_vs_gap, flow_vs_distance, clogging, models, screen_confirm");
      r.kinds.push_back(k.as_string()->get());
    }
  }
  if (auto b = t.text("baseline", true)) r.baseline = *b;
  r.j = one_of(t, "j", kJKinds, r.j);
  r.pairing = one_of(t, "pairing", {"unpaired", "paired"}, r.pairing);
  for (const char* k : {"fit_w_min", "fit_w_max"})  // read by the report (studies/report.cpp)
    if (const toml::node* n = t.get(k); n && !(number_value(*n) && std::isfinite(*number_value(*n))))
      t.fail(k, *n, "must be a finite number (W/d)");
  return r;
}

// Sequential replication: replicates is the minimum, replicates_max the cap (studies/sequential.hpp).
void read_sequential(StrictTable& t, StudyDef& d) {
  SequentialDef& q = d.sequential;
  const auto target = t.number("replicates_target_halfwidth", 0, 1);
  if (!target) {
    for (const char* k : {"replicates_max", "replicates_batch"})
      if (const toml::node* n = t.get(k))
        t.fail(k, *n, "only with replicates_target_halfwidth (sequential replication)");
    return;
  }
  if (!(*target > 0)) t.fail("replicates_target_halfwidth", *t.get("replicates_target_halfwidth"),
                             "must be a number in (0, 1]: the relative half-width, e.g. 0.02 for +-2 %");
  q.enabled = true;
  q.target_halfwidth = *target;
  const auto max = t.integer("replicates_max", 1, kMaxReplicates);
  if (!max) t.missing("replicates_max", "required with replicates_target_halfwidth: the cap per point, e.g. 40");
  q.max_replicates = static_cast<int>(*max);
  if (auto b = t.integer("replicates_batch", 1, kMaxReplicates)) q.batch = static_cast<int>(*b);
  if (d.replicates < kMinSequentialReplicates) {
    const toml::node* r = t.get("replicates");
    t.fail(r ? "replicates" : "replicates_target_halfwidth", r ? *r : *t.get("replicates_target_halfwidth"),
           fmt::format("with replicates_target_halfwidth, replicates (the minimum before the first look) must be "
                       ">= {}: fewer makes stopping on a narrow interval bias it",
                       kMinSequentialReplicates));
  }
  if (q.max_replicates < d.replicates)
    t.fail("replicates_max", *t.get("replicates_max"), fmt::format("must be >= replicates ({})", d.replicates));
}

void read_study_section(StrictTable t, StudyDef& d) {
  auto name = t.text("name", true);
  if (!name) t.missing("name", "required: a non-empty string (also the output folder results/<name>/)");
  d.name = *name;
  if (name->find_first_of("/\\") != std::string::npos)
    t.fail("name", *t.get("name"), "must not contain / or \\ (it names a folder)");
  if (auto desc = t.text("description")) d.description = *desc;
  if (auto r = t.integer("replicates", 1, kMaxReplicates)) d.replicates = static_cast<int>(*r);
  d.models = read_models(t);
  if (auto seed = t.integer("seed", 0)) d.seed = static_cast<std::uint64_t>(*seed);
  d.set = read_set(t);
  read_sequential(t, d);
}

}  // namespace

StudyDef parse_study(std::string_view text, std::string_view source_name, const std::filesystem::path& base_dir) {
  const std::string source(source_name);
  toml::table doc = parse_toml_located(text, source);
  StudyDef d;
  StrictTable root(&doc, "", source, kRootKeys);
  const toml::table* study = root.table("study");
  if (!study) throw ScenarioError({source, 1, 1}, "study", "", "required: a [study] section with name");
  read_study_section(StrictTable(study, "study", source, kStudyKeys), d);
  std::set<std::string> labels;
  for (const toml::table* t : table_array(root, "series", "[[series]]")) {
    SeriesDef s = read_series(StrictTable(t, "series", source, kSeriesKeys), source, base_dir);
    if (!labels.insert(s.label).second)
      throw ScenarioError(location_of(source, *t->get("label")), "series.label", "\"" + s.label + "\"",
                          "must be unique in the study");
    d.series.push_back(std::move(s));
  }
  if (const toml::table* sc = root.table("screen")) {
    if (d.sequential.enabled)  // the screen decides its own replicates round by round
      throw ScenarioError(location_of(source, *study->get("replicates_target_halfwidth")),
                          "study.replicates_target_halfwidth", toml_text(*study->get("replicates_target_halfwidth")),
                          "not allowed beside [screen]: the screen allocates replicates by its own rounds");
    read_screen(doc, *sc, source, base_dir, d);
    for (const SeriesDef& s : d.series) labels.insert(s.label);
  }
  if (d.series.empty()) throw ScenarioError({source, 1, 1}, "series", "", "required: at least one [[series]]");
  if (const toml::table* pm = root.table("per_model")) {
    StrictTable plans(pm, "per_model", source, kModelNames);
    for (const std::string& name : kModelNames)
      if (const toml::table* t = plans.table(name)) {
        d.per_model[parse_model_kind(name)] = read_plan(StrictTable(t, "per_model." + name, source, kPlanKeys));
        check_sequential_plan(d, d.per_model[parse_model_kind(name)], StrictTable(t, "per_model." + name, source, kPlanKeys));
      }
  }
  if (const toml::table* q = root.table("quick")) d.quick = read_quick(StrictTable(q, "quick", source, kQuickKeys));
  if (const toml::table* c = root.table("confirm"))
    d.confirm = read_confirm(StrictTable(c, "confirm", source, kConfirmKeys));
  if (const toml::table* r = root.table("report")) {
    StrictTable rt(r, "report", source, kReportKeys);
    d.report = read_report(rt);
    if (!d.report.baseline.empty() && !labels.count(d.report.baseline))
      rt.fail("baseline", *r->get("baseline"), "must be the label of one of the study's [[series]]");
    if (d.screen && d.report.j != "paper")
      rt.fail("j", *r->get("j"),
              "a [screen] races J_paper cut at the time limit (README \"Screens (racing)\"): leave j out or set "
              "\"paper\"");
  }
  return d;
}

StudyDef load_study(const std::filesystem::path& file) {
  StudyDef d = parse_study(read_input_file(file, "study file"), file.string(), file.parent_path());
  d.file = file;
  return d;
}

bool thin_keeps(std::size_t i, std::size_t n, int thin) {
  return i % static_cast<std::size_t>(std::max(1, thin)) == 0 || i + 1 == n;
}

std::vector<AxisValue> thin_values(const std::vector<AxisValue>& values, int thin) {
  std::vector<AxisValue> out;
  for (std::size_t i = 0; i < values.size(); ++i)
    if (thin_keeps(i, values.size(), thin)) out.push_back(values[i]);
  return out;
}

int replicates_for(const StudyDef& study, ModelKind model) {
  auto it = study.per_model.find(model);
  return it != study.per_model.end() && it->second.replicates ? *it->second.replicates : study.replicates;
}

int max_replicates_for(const StudyDef& study, ModelKind model) {
  const int min = replicates_for(study, model);
  return study.sequential.enabled ? std::max(min, study.sequential.max_replicates) : min;
}

int thin_for(const StudyDef& study, ModelKind model) {
  auto it = study.per_model.find(model);
  return it != study.per_model.end() ? it->second.thin : 1;
}

StudyDef apply_quick(StudyDef study) {
  if (study.quick.replicates) study.replicates = *study.quick.replicates;
  if (study.quick.models) study.models = *study.quick.models;
  if (study.quick.replicates) study.confirm.replicates = std::min(study.confirm.replicates, *study.quick.replicates);
  for (auto& [model, plan] : study.per_model) {  // --quick: one budget for every model, the same models
    plan.replicates.reset();
    plan.thin = 1;
  }
  study.sequential = {};     // --quick: a fixed count, a first look (README "Sequential replication")
  for (SeriesDef& s : study.series)
    for (SweepAxis& a : s.axes) a.values = thin_values(a.values, study.quick.thin);
  return study;
}

}  // namespace gapflow

// [screen] loader: strict keys, values in d or mm, the grid as series (studies/screen_def.hpp).
#include "studies/screen_loader.hpp"

#include "common/input_bounds.hpp"
#include "common/text_file.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <set>

namespace gapflow {

namespace {

const std::vector<std::string> kScreenKeys{
    "scenario", "shapes",     "cylinder_diameter_d", "cylinder_diameter_mm", "triangle_side_d", "triangle_side_mm",
    "distance_d", "distance_mm", "gap_d", "gap_mm",  "reference", "initial", "step", "max", "confirm", "baseline_confirm", "alpha",
    "drop_below", "best_margin", "confidence", "scope", "check_model", "check_replicates", "check_controls"};
const std::vector<std::string> kScreenShapes{"cylinder", "A", "V"};

// One grid axis as written: its values (in the unit of the key that gave them) and where.
struct LengthList {
  std::vector<double> values;
  std::vector<SourceLocation> where;
  bool in_d = false;
  std::string key;  // the key that gave it ("" = absent)
};

// `<name>_d` or `<name>_mm`: a non-empty list of distinct finite numbers >= lo (> 0 when positive).
LengthList read_lengths(StrictTable& t, const std::string& name, bool positive, bool required,
                        const std::string& meaning) {
  LengthList out;
  const std::string kd = name + "_d", kmm = name + "_mm";
  const toml::node *nd = t.get(kd), *nmm = t.get(kmm);
  if (nd && nmm) t.fail(kmm, *nmm, fmt::format("give either {} or {}, not both", kd, kmm));
  if (!nd && !nmm) {
    if (required) t.missing(kd, fmt::format("required: {} as {} (in d) or {} (in mm)", meaning, kd, kmm));
    return out;
  }
  out.in_d = nd != nullptr;
  out.key = out.in_d ? kd : kmm;
  const toml::array* a = t.array(out.key, "numbers");
  const std::string allowed = fmt::format("must be a non-empty list of at most {} distinct numbers {} ({})",
                                          kMaxAxisValues, positive ? "> 0" : ">= 0", out.in_d ? "d" : "mm");
  if (a->empty() || a->size() > static_cast<std::size_t>(kMaxAxisValues)) t.fail(out.key, *a, allowed);
  for (const toml::node& n : *a) {
    const std::optional<double> v = n.value<double>();
    const bool ok = n.is_number() && v && std::isfinite(*v) && (positive ? *v > 0 : *v >= 0) &&
                    std::find(out.values.begin(), out.values.end(), *v) == out.values.end();
    if (!ok) throw ScenarioError(t.at(n), t.dotted(out.key), toml_text(n), allowed);
    out.values.push_back(*v);
    out.where.push_back(t.at(n));
  }
  return out;
}

// mm, rounded to 1 nm so that a value in d reads back the same in every job key.
double to_mm(const LengthList& l, std::size_t i, double d_mm) {
  const double mm = l.in_d ? l.values[i] * d_mm : l.values[i];
  return std::stod(fmt::format("{:.6f}", mm));
}

SweepAxis axis_of(const std::string& key, const LengthList& l, double d_mm, std::vector<double>& mm_out) {
  SweepAxis a{key, {}};
  for (std::size_t i = 0; i < l.values.size(); ++i) {
    const double mm = to_mm(l, i, d_mm);
    mm_out.push_back(mm);
    a.values.push_back({number_text(mm), number_text(mm), l.where[i]});
  }
  return a;
}

// The nominal d of the base scenario with the study's overrides.
double base_diameter_mm(const std::filesystem::path& scenario, const SourceLocation& where, const StudyDef& study) {
  std::string text;
  try {
    text = read_input_file(scenario, "scenario file");
  } catch (const FileError& e) {
    throw ScenarioError(where, "screen.scenario", "\"" + scenario.string() + "\"",
                        e.reason() + " (relative to the study file)");
  }
  std::vector<std::string> overrides;
  for (const LocatedOverride& o : study.set) overrides.push_back(o.text);
  return parse_scenario(text, scenario.string(), overrides).def.particles.diameter_mm;
}

void read_racing(StrictTable& t, RacingParams& r) {
  if (auto v = t.integer("initial", 2, kMaxReplicates)) r.initial = static_cast<int>(*v);
  if (auto v = t.integer("step", 1, kMaxReplicates)) r.step = static_cast<int>(*v);
  r.max = r.initial + 3 * r.step;
  if (auto v = t.integer("max", r.initial, kMaxReplicates)) r.max = static_cast<int>(*v);
  if (auto v = t.integer("confirm", 2, kMaxReplicates)) r.confirm = static_cast<int>(*v);
  // At least confirm: a baseline is compared with every survivor at its gap (Dunnett: more, never fewer).
  if (auto v = t.integer("baseline_confirm", r.confirm, kMaxReplicates)) r.baseline_confirm = static_cast<int>(*v);
  if (auto v = t.number("alpha", 1e-6, 0.5)) r.alpha = *v;
  if (auto v = t.number("drop_below", 0.01, 100)) r.drop_below = *v;
  if (auto v = t.number("best_margin", 0, 100)) r.best_margin = *v;
  if (auto v = t.number("confidence", 0.5, 0.9999)) r.confidence = *v;
  r.family = t.choice("scope", {"cell", "family"}).value_or("cell") == "family";
}

// The other model's check of the screen's picks: check_model must differ from the screen's.
void read_check(StrictTable& t, ModelKind screen_model, ScreenDef& s) {
  const bool any = t.get("check_replicates") || t.get("check_controls");
  if (auto m = t.choice("check_model", {"2d", "3d"})) {
    s.check_model = parse_model_kind(*m);
    if (*s.check_model == screen_model)
      t.fail("check_model", *t.get("check_model"),
             "must be the other model than the screen's (study.models): the check confirms the screen's cells "
             "with a model that did not pick them");
  } else if (any) {
    const char* key = t.get("check_replicates") ? "check_replicates" : "check_controls";
    t.fail(key, *t.get(key), "needs check_model (\"2d\" or \"3d\"): without it the screen checks nothing");
  }
  if (auto v = t.integer("check_replicates", 2, kMaxReplicates)) s.check_replicates = static_cast<int>(*v);
  if (auto v = t.integer("check_controls", 0, 100)) s.check_controls = static_cast<int>(*v);
}

}  // namespace

const char* screen_size_key(const std::string& shape) {
  return shape == "cylinder" ? "obstruction.diameter_mm" : "obstruction.side_mm";
}

void read_screen(const toml::table& root, const toml::table& screen, const std::string& source,
                 const std::filesystem::path& base_dir, StudyDef& study) {
  StrictTable t(&screen, "screen", source, kScreenKeys);
  for (const char* other : {"series", "confirm"})
    if (const toml::node* n = root.get(other))
      throw ScenarioError(location_of(t.here().source, *n), other, "",
                          "not allowed beside [screen]: the screen makes its own series from its grid "
                          "(and its confirmation is its final round)");
  if (study.models.size() != 1)
    throw ScenarioError(t.here(), "study.models", "", "a [screen] runs one model: [\"2d\"] or [\"3d\"]");
  ScreenDef s;
  auto scenario = t.text("scenario", true);
  if (!scenario) t.missing("scenario", "required: the base scenario file, relative to the study file");
  s.scenario = base_dir / *scenario;
  const SourceLocation scenario_where = t.at(*t.get("scenario"));
  const toml::array* shapes = t.array("shapes", "shape names");
  if (!shapes) t.missing("shapes", "required: a list of \"cylinder\", \"A\", \"V\"");
  const std::string shapes_allowed = "must be a non-empty list of distinct shapes, each \"cylinder\", \"A\" or \"V\"";
  for (const toml::node& n : *shapes) {
    const std::string v = n.value<std::string>().value_or("");
    if (std::find(kScreenShapes.begin(), kScreenShapes.end(), v) == kScreenShapes.end() ||
        std::find(s.shapes.begin(), s.shapes.end(), v) != s.shapes.end())
      throw ScenarioError(t.at(n), t.dotted("shapes"), toml_text(n), shapes_allowed);
    s.shapes.push_back(v);
  }
  if (s.shapes.empty()) t.fail("shapes", *shapes, shapes_allowed);
  const bool cylinder = std::count(s.shapes.begin(), s.shapes.end(), "cylinder") > 0;
  const bool triangle = s.shapes.size() > (cylinder ? 1u : 0u);
  const LengthList cyl = read_lengths(t, "cylinder_diameter", true, cylinder, "the cylinder diameters");
  const LengthList tri = read_lengths(t, "triangle_side", true, triangle, "the triangle sides (A and V)");
  for (const LengthList* unused : {cylinder ? nullptr : &cyl, triangle ? nullptr : &tri})
    if (unused && !unused->key.empty())
      t.fail(unused->key, *t.get(unused->key), "no shape in `shapes` uses it: remove it or add the shape");
  const LengthList dist = read_lengths(t, "distance", false, true, "the distances D from the gap line");
  const LengthList gap = read_lengths(t, "gap", true, true, "the gaps W");
  s.reference = t.choice("reference", {"nearest", "centre"}).value_or("nearest");
  read_racing(t, s.racing);
  read_check(t, study.models.front(), s);
  s.d_mm = base_diameter_mm(s.scenario, scenario_where, study);

  std::vector<double> ignored;
  const SweepAxis d_axis = axis_of("obstruction.distance_mm", dist, s.d_mm, s.distance_mm);
  const SweepAxis w_axis = axis_of("bottleneck.gap_mm", gap, s.d_mm, s.gap_mm);
  if (cylinder) axis_of("", cyl, s.d_mm, s.cylinder_diameter_mm);
  if (triangle) axis_of("", tri, s.d_mm, s.triangle_side_mm);
  double cells = 0;
  for (const std::string& shape : s.shapes) {
    const LengthList& sizes = shape == "cylinder" ? cyl : tri;
    SeriesDef series{shape, s.scenario, scenario_where, {}, {}};
    series.set = {{"obstruction.shape=" + shape, scenario_where},
                  {"obstruction.reference=" + s.reference, scenario_where}};
    series.axes = {axis_of(screen_size_key(shape), sizes, s.d_mm, ignored), d_axis, w_axis};
    cells += static_cast<double>(sizes.values.size() * dist.values.size() * gap.values.size());
    study.series.push_back(std::move(series));
  }
  SeriesDef none{kScreenBaseline, s.scenario, scenario_where, {{"obstruction.shape=none", scenario_where}}, {w_axis}};
  study.series.push_back(std::move(none));
  const double check = s.check_model ? s.check_replicates : 0;
  const double most = static_cast<double>(most_race_runs(s.racing, static_cast<std::size_t>(cells), gap.values.size())) +
                      (cells + static_cast<double>(gap.values.size())) * check;
  if (most > static_cast<double>(kMaxStudyJobs))
    t.missing("max", fmt::format("the screen may need {:.6g} runs (cells x (max + confirm + check_replicates) + gaps x "
                                 "(max + baseline_confirm + check_replicates)); at most {} "
                                 "are allowed: split it",
                                 most, kMaxStudyJobs));
  study.report.baseline = kScreenBaseline;
  study.screen = std::move(s);
}

}  // namespace gapflow

#include "calibrate/data_file.hpp"

#include "common/geometry.hpp"
#include "common/text_file.hpp"
#include "common/toml_parse.hpp"
#include "common/toml_strict.hpp"

#include <fmt/format.h>

#include <cmath>
#include <set>
#include <sstream>

namespace gapflow {

const char* to_string(ObservableKind k) {
  switch (k) {
    case ObservableKind::j_paper: return "j_paper";
    case ObservableKind::j_mid: return "j_mid";
    case ObservableKind::j_flowing: return "j_flowing";
    case ObservableKind::j_star: return "j_star";
    case ObservableKind::mean_avalanche: return "mean_avalanche";
    case ObservableKind::ln_s_plus_1: return "ln_s_plus_1";
    case ObservableKind::clog_share: return "clog_share";
    case ObservableKind::front_arrival: return "front_arrival";
    case ObservableKind::exit_offset: return "exit_offset";
    case ObservableKind::exit_spread: return "exit_spread";
  }
  return "?";
}

FitScale default_scale(ObservableKind k) {
  // An offset is signed (0 at the gap's centre): linear like a share and a logarithm.
  return k == ObservableKind::ln_s_plus_1 || k == ObservableKind::clog_share || k == ObservableKind::exit_offset
             ? FitScale::linear
             : FitScale::log;
}

double to_fit_scale(FitScale scale, double v) { return scale == FitScale::log ? std::log(v) : v; }
double from_fit_scale(FitScale scale, double v) { return scale == FitScale::log ? std::exp(v) : v; }

namespace {

const std::vector<std::string> kRootKeys{"data", "source", "model", "observable", "floors",
                                         "design", "free", "points", "point"};
const std::vector<std::string> kDataKeys{"name", "description"};
const std::vector<std::string> kSourceKeys{"citation", "method", "uncertainty"};
const std::vector<std::string> kModelKeys{"scenario", "set", "replicates", "seed"};
const std::vector<std::string> kObservableKeys{"kind", "scale", "uncertainty", "floor_relative"};
const std::vector<std::string> kFloorKeys{"relative", "absolute"};
const std::vector<std::string> kDesignKeys{"column", "key", "unit"};
const std::vector<std::string> kFreeKeys{"key", "lo", "hi", "step", "measured", "measured_se"};
const std::vector<std::string> kPointsKeys{"csv"};
const std::vector<std::string> kMethods{"measured", "digitized", "simulated"};
const std::vector<std::string> kKinds{"j_paper", "j_mid", "j_flowing", "j_star", "mean_avalanche", "ln_s_plus_1",
                                      "clog_share",   "front_arrival", "exit_offset", "exit_spread"};
const std::vector<std::string> kValueColumns{"value", "uncertainty", "replicates", "held_out", "observable"};

ObservableKind kind_named(const std::string& name) {
  for (std::size_t i = 0; i < kKinds.size(); ++i)
    if (kKinds[i] == name) return static_cast<ObservableKind>(i);
  throw std::logic_error("unknown observable " + name);
}

// A share and a signed offset can be 0 or negative: never on a log scale.
bool log_scale_allowed(ObservableKind k) { return k != ObservableKind::clog_share && k != ObservableKind::exit_offset; }

// The seed and the replicate are the calibration's (common random numbers).
bool reserved_key(const std::string& key) { return key == "run.seed" || key == "run.replicate"; }

std::vector<const toml::table*> tables_of(StrictTable& root, std::string_view key, const char* what) {
  std::vector<const toml::table*> out;
  const toml::array* a = root.array(key, what);
  if (!a) return out;
  for (const toml::node& n : *a) {
    if (!n.is_table()) root.fail(key, n, fmt::format("must be an array of tables {}", what));
    out.push_back(n.as_table());
  }
  return out;
}

std::string required_text(StrictTable& t, std::string_view key, const char* what) {
  auto v = t.text(key, true);
  if (!v) t.missing(key, fmt::format("required: {}", what));
  return *v;
}

void read_source(StrictTable t, DataSource& s) {
  s.citation = required_text(t, "citation", "where the numbers come from (a citation)");
  const auto method = t.choice("method", kMethods);
  if (!method) t.missing("method", "required: one of \"measured\", \"digitized\", \"simulated\"");
  s.method = *method;
  s.uncertainty = required_text(t, "uncertainty", "how the uncertainties were obtained");
}

void read_model(StrictTable t, DataFile& d, const std::filesystem::path& base_dir) {
  d.scenario = base_dir / required_text(t, "scenario", "the scenario template, relative to the data file");
  if (const toml::array* a = t.array("set", "\"key=value\" strings")) {
    for (const toml::node& n : *a) {
      if (!n.is_string() || n.as_string()->get().find('=') == std::string::npos)
        t.fail("set", n, "each entry must be a \"key=value\" string, e.g. \"particles.count=150\"");
      const std::string text = n.as_string()->get();
      if (reserved_key(text.substr(0, text.find('='))))
        t.fail("set", n, "run.seed and run.replicate are the calibration's: use [model] seed and replicates");
      d.set.push_back(text);
    }
  }
  if (auto r = t.integer("replicates", 2)) {
    if (*r > 1000) t.fail("replicates", *t.get("replicates"), "must be an integer in [2, 1000]");
    d.model_replicates = static_cast<int>(*r);
  }
  if (auto s = t.integer("seed", 0)) d.seed = static_cast<std::uint64_t>(*s);
}

void read_observable(StrictTable t, DataFile& d, std::string& uncertainty_kind) {
  const auto kind = t.choice("kind", kKinds);
  if (!kind) t.missing("kind", fmt::format("required: one of {}", fmt::join(kKinds, ", ")));
  d.observable = kind_named(*kind);
  d.scale = default_scale(d.observable);
  if (auto s = t.choice("scale", {"log", "linear"})) d.scale = *s == "log" ? FitScale::log : FitScale::linear;
  if (d.scale == FitScale::log && !log_scale_allowed(d.observable))
    t.fail("scale", *t.get("scale"), "a share or an offset can be 0 or negative: use \"linear\"");
  uncertainty_kind = t.choice("uncertainty", {"se", "ci95"}).value_or("se");
  d.floor_relative = t.number("floor_relative", 0, 1).value_or(0.0);
}

DesignColumn read_design(StrictTable t) {
  DesignColumn c;
  c.where = t.here();
  c.column = required_text(t, "column", "the column's name in the points");
  if (std::find(kValueColumns.begin(), kValueColumns.end(), c.column) != kValueColumns.end())
    t.fail("column", *t.get("column"), "must not be one of value, uncertainty, replicates, held_out, observable");
  c.key = required_text(t, "key", "the scenario key the column sets, e.g. \"bottleneck.gap_mm\"");
  if (reserved_key(c.key)) t.fail("key", *t.get("key"), "run.seed and run.replicate are the calibration's");
  c.in_diameters = t.choice("unit", {"d", "lab"}).value_or("lab") == "d";
  if (c.in_diameters && c.key == "particles.diameter_mm")
    t.fail("unit", *t.get("unit"), "must be \"lab\" for particles.diameter_mm (the size cannot be counted in sizes)");
  return c;
}

FreeParameter read_free(StrictTable t) {
  FreeParameter f;
  f.where = t.here();
  f.key = required_text(t, "key", "the scenario key the fit may move");
  if (reserved_key(f.key)) t.fail("key", *t.get("key"), "run.seed and run.replicate are the calibration's");
  constexpr double big = 1e12;
  const auto lo = t.number("lo", -big, big), hi = t.number("hi", -big, big), step = t.number("step", 0, big);
  if (!lo) t.missing("lo", "required: the lower bound (key units)");
  if (!hi) t.missing("hi", "required: the upper bound (key units)");
  if (*hi <= *lo) t.fail("hi", *t.get("hi"), fmt::format("must be > lo ({})", *lo));
  f.lo = *lo;
  f.hi = *hi;
  f.step = step.value_or((*hi - *lo) / 6);
  if (f.step <= 0 || f.step > f.hi - f.lo) t.fail("step", *t.get("step"), "must be > 0 and <= hi - lo");
  // A reading may lie outside [lo, hi] (that bounds the fit, not a noisy measurement).
  const auto measured = t.number("measured", -big, big), measured_se = t.number("measured_se", -big, big);
  if (measured && !measured_se) t.missing("measured_se", "required with measured: its standard error (key units, > 0)");
  if (measured_se && !measured) t.missing("measured", "required with measured_se: the measured value (key units)");
  if (measured_se && *measured_se <= 0) t.fail("measured_se", *t.get("measured_se"), "must be a number > 0 (a standard error, key units)");
  f.measured = measured.value_or(0.0);
  f.measured_se = measured_se.value_or(0.0);
  return f;
}

// A design value as the scenario loader reads it (numbers and strings only).
std::string design_literal(const toml::node& n, const StrictTable& t, const std::string& column) {
  if (n.is_number()) {
    const double v = n.value<double>().value();
    if (!std::isfinite(v)) t.fail(column, n, "must be a finite number");
    return number_text(v);
  }
  if (n.is_string()) return toml_text(n);
  t.fail(column, n, "must be a number or a string");
}

// One [floors] entry: which observable, its floor, and where it stands (for the check that a point measures it).
struct FloorEntry {
  ObservableKind observable;
  SeFloor floor;
  SourceLocation where;
};

// [floors]: one entry per observable named, each an inline table with relative and/or absolute. Read in
// the observables' order (a TOML table keeps no file order): of several bad entries, that one is named.
std::vector<FloorEntry> read_floors(const toml::table& t, const std::string& source) {
  StrictTable floors(&t, "floors", source, kKinds);
  std::vector<FloorEntry> out;
  for (const std::string& kind : kKinds) {
    const toml::node* n = floors.get(kind);
    if (!n) continue;
    if (!n->is_table()) floors.fail(kind, *n, "must be an inline table, e.g. { relative = 0.01 } or { absolute = 0.1 }");
    StrictTable e(n->as_table(), "floors." + kind, source, kFloorKeys);
    const auto relative = e.number("relative", 0, 1);
    const auto absolute = e.number("absolute", 0, 1e300);
    if (!relative && !absolute)
      e.missing("relative", "required: relative (a share of the value) and/or absolute (in the observable's unit)");
    out.push_back({kind_named(kind), {relative.value_or(0.0), absolute.value_or(0.0)}, floors.at(*n)});
  }
  return out;
}

// Turn the file's uncertainty into a standard error, with the floor.
double standard_error(double u, double value, const std::string& kind, SeFloor floor) {
  const double se = kind == "ci95" ? u / 1.959963984540054 : u;
  // Two-argument hypot, then the absolute floor: the three-argument form rounds differently in 4 of 10
  // cases with the absolute floor 0, which moved every baseline fit made before [floors] by ~1e-8.
  return std::hypot(std::hypot(se, floor.relative * std::abs(value)), floor.absolute);
}

DataPoint read_point(StrictTable t, const DataFile& d, const std::string& uncertainty_kind) {
  DataPoint p;
  p.where = t.here();
  for (const DesignColumn& c : d.design) {
    const toml::node* n = t.get(c.column);
    if (!n) t.missing(c.column, fmt::format("required: the design column '{}' (sets {})", c.column, c.key));
    if (c.in_diameters && !n->is_number())
      t.fail(c.column, *n, fmt::format("must be a number (a length in particle diameters, unit \"d\")"));
    p.design.push_back(design_literal(*n, t, c.column));
  }
  p.observable = d.observable;
  p.scale = d.scale;
  if (auto kind = t.choice("observable", kKinds)) {
    p.observable = kind_named(*kind);
    if (p.observable != d.observable) p.scale = default_scale(p.observable);
  }
  const auto value = t.number("value", -1e300, 1e300);
  if (!value) t.missing("value", fmt::format("required: the measured {}", to_string(p.observable)));
  if (p.scale == FitScale::log && *value <= 0)
    t.fail("value", *t.get("value"), fmt::format("must be > 0 ({} is fitted on a log scale)", to_string(p.observable)));
  const auto u = t.number("uncertainty", 0, 1e300);
  if (!u) t.missing("uncertainty", fmt::format("required: the value's {}", uncertainty_kind));
  p.value = *value;
  p.se = standard_error(*u, p.value, uncertainty_kind, d.floor_of(p.observable));
  if (p.se <= 0) t.fail("uncertainty", *t.get("uncertainty"), "must be > 0 (or set a floor: [observable] floor_relative, [floors])");
  if (auto r = t.integer("replicates", 1)) p.replicates = static_cast<int>(*r);
  p.held_out = t.boolean("held_out").value_or(false);
  return p;
}

std::vector<std::string> point_columns(const DataFile& d) {
  std::vector<std::string> cols;
  for (const DesignColumn& c : d.design) cols.push_back(c.column);
  cols.insert(cols.end(), kValueColumns.begin(), kValueColumns.end());
  return cols;
}

// A CSV of points: '#' comments, a header naming every design column, value and
// uncertainty (replicates, held_out optional). Each row becomes a TOML table so
// that it is validated exactly like an inline [[point]].
std::vector<DataPoint> read_csv_points(const std::filesystem::path& csv, const SourceLocation& from, const DataFile& d,
                                       const std::string& uncertainty_kind) {
  std::optional<std::string> text;
  try {
    text = read_input_file(csv, "CSV file of points");
  } catch (const FileError& e) {  // said where the data file names it
    throw ScenarioError(from, "points.csv", "\"" + csv.string() + "\"", "cannot be read: " + e.reason());
  }
  std::istringstream in(*text);
  std::string line;
  std::vector<std::string> header;
  std::vector<DataPoint> out;
  const std::vector<std::string> allowed = point_columns(d);
  for (int line_no = 1; std::getline(in, line); ++line_no) {
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line.empty() || line[0] == '#') continue;
    std::vector<std::string> cells;
    std::stringstream ss(line);
    for (std::string c; std::getline(ss, c, ',');) cells.push_back(c);
    const SourceLocation at{csv.string(), line_no, 1};
    if (header.empty()) {
      for (const std::string& h : cells)
        if (std::find(allowed.begin(), allowed.end(), h) == allowed.end())
          throw ScenarioError(at, h, "",
                              "unknown column; allowed: design columns, value, uncertainty, replicates, held_out, observable");
      header = cells;
      continue;
    }
    if (cells.size() != header.size())
      throw ScenarioError(at, "", line, fmt::format("has {} fields; the header has {}", cells.size(), header.size()));
    std::string row;
    for (std::size_t i = 0; i < cells.size(); ++i) {
      const bool is_number = !cells[i].empty() && cells[i].find_first_not_of("0123456789+-.eE") == std::string::npos;
      const bool is_bool = cells[i] == "true" || cells[i] == "false";
      row += header[i] + " = " + (is_number || is_bool ? cells[i] : "\"" + cells[i] + "\"") + "\n";
    }
    toml::table t;
    try {
      t = toml::parse(row, csv.string());
    } catch (const toml::parse_error& e) {
      throw ScenarioError(at, "", line, std::string(e.description()));
    }
    // Locate errors on the CSV line (the table's own positions are of the synthetic text).
    try {
      out.push_back(read_point(StrictTable(&t, "point", csv.string(), allowed), d, uncertainty_kind));
    } catch (const ScenarioError& e) {
      throw ScenarioError(at, e.key(), e.value(), e.allowed());
    }
    out.back().where = at;
  }
  return out;
}

}  // namespace

DataFile parse_data_file(std::string_view text, std::string_view source_name, const std::filesystem::path& base_dir) {
  const std::string source(source_name);
  toml::table doc = parse_toml_located(text, source);
  DataFile d;
  StrictTable root(&doc, "", source, kRootKeys);
  const toml::table* data = root.table("data");
  if (!data) throw ScenarioError({source, 1, 1}, "data", "", "required: a [data] section with name");
  StrictTable dt(data, "data", source, kDataKeys);
  d.name = required_text(dt, "name", "a non-empty string (also the output folder results/calibration/<name>/)");
  if (d.name.find_first_of("/\\") != std::string::npos) dt.fail("name", *dt.get("name"), "must not contain / or \\");
  d.description = dt.text("description").value_or("");
  const toml::table* source_t = root.table("source");
  if (!source_t) throw ScenarioError({source, 1, 1}, "source", "", "required: [source] with citation, method, uncertainty");
  read_source(StrictTable(source_t, "source", source, kSourceKeys), d.source);
  const toml::table* model = root.table("model");
  if (!model) throw ScenarioError({source, 1, 1}, "model", "", "required: [model] with the scenario template");
  read_model(StrictTable(model, "model", source, kModelKeys), d, base_dir);
  const toml::table* obs = root.table("observable");
  if (!obs) throw ScenarioError({source, 1, 1}, "observable", "", "required: [observable] with kind");
  std::string uncertainty_kind;
  read_observable(StrictTable(obs, "observable", source, kObservableKeys), d, uncertainty_kind);
  std::vector<FloorEntry> floors;
  if (const toml::table* t = root.table("floors")) floors = read_floors(*t, source);
  for (const FloorEntry& f : floors) d.floors.emplace_back(f.observable, f.floor);
  std::set<std::string> names;
  for (const toml::table* t : tables_of(root, "design", "[[design]]")) {
    d.design.push_back(read_design(StrictTable(t, "design", source, kDesignKeys)));
    if (!names.insert(d.design.back().column).second)
      throw ScenarioError(d.design.back().where, "design.column", d.design.back().column, "appears twice");
  }
  if (d.design.empty()) throw ScenarioError({source, 1, 1}, "design", "", "required: at least one [[design]] column");
  for (const toml::table* t : tables_of(root, "free", "[[free]]")) d.free.push_back(read_free(StrictTable(t, "free", source, kFreeKeys)));
  if (d.free.size() > 3)
    throw ScenarioError(d.free[3].where, "free", d.free[3].key, "at most 3 free parameters (the fit is a grid / BOBYQA)");
  const toml::table* points = root.table("points");
  const auto inline_points = tables_of(root, "point", "[[point]]");
  if (points && !inline_points.empty())
    throw ScenarioError({source, 1, 1}, "points", "", "give the points either as [points] csv or as [[point]] rows, not both");
  if (points) {
    StrictTable pt(points, "points", source, kPointsKeys);
    const std::string csv = required_text(pt, "csv", "the CSV file of points, relative to the data file");
    d.points = read_csv_points(base_dir / csv, pt.at(*pt.get("csv")), d, uncertainty_kind);
  }
  for (const toml::table* t : inline_points)
    d.points.push_back(read_point(StrictTable(t, "point", source, point_columns(d)), d, uncertainty_kind));
  if (d.points.size() < 2) throw ScenarioError({source, 1, 1}, "point", "", "required: at least 2 points");
  // A floor no point uses is a mix-up of two observables' names more often than not.
  for (const FloorEntry& f : floors)
    if (std::none_of(d.points.begin(), d.points.end(), [&](const DataPoint& p) { return p.observable == f.observable; }))
      throw ScenarioError(f.where, std::string("floors.") + to_string(f.observable), "",
                          fmt::format("no point measures {}: a floor for an observable of the points", to_string(f.observable)));
  if (d.fitted_count() <= d.free.size())
    throw ScenarioError({source, 1, 1}, "point.held_out", "",
                        fmt::format("needs more fitted (not held-out) points than free parameters ({})", d.free.size()));
  // Every point must make a valid scenario (loaded and compiled): check now, located at the point.
  for (std::size_t i = 0; i < d.points.size(); ++i) {
    try {
      const LoadedScenario loaded = d.point_scenario(i);
      try {
        (void)compile_scenario(loaded.def);
      } catch (const ScenarioInvalid& e) {
        throw locate(e, loaded);
      }
    } catch (const ScenarioError& e) {
      throw ScenarioError(d.points[i].where, e.key(), e.value(), fmt::format("{} [point {}]", e.allowed(), d.point_label(i)));
    }
  }
  for (const FreeParameter& f : d.free) {
    try {
      (void)d.point_scenario(0, {fmt::format("{}={}", f.key, number_text(f.lo)), fmt::format("{}={}", f.key, number_text(f.hi))});
    } catch (const ScenarioError& e) {
      throw ScenarioError(f.where, f.key, e.value(), "the range must be valid for the scenario: " + e.allowed());
    }
  }
  return d;
}

DataFile load_data_file(const std::filesystem::path& file) {
  DataFile d = parse_data_file(read_input_file(file, "data file"), file.string(), file.parent_path());
  d.file = file;
  return d;
}

void check_points_run_in(const DataFile& data, ModelKind model) {
  for (std::size_t i = 0; i < data.points.size(); ++i) {
    const LoadedScenario loaded = data.point_scenario(i);
    try {
      check_model_supports(compile_scenario(loaded.def), model);
    } catch (const ScenarioInvalid& e) {
      const ScenarioError at = locate(e, loaded);
      throw ScenarioError(data.points[i].where, at.key(), at.value(),
                          fmt::format("{} [point {}, {} model]", at.allowed(), data.point_label(i), to_string(model)));
    }
  }
}

std::vector<std::string> DataFile::point_overrides(std::size_t i) const {
  // Columns in lab units first: one of them may be the particle size itself, and a
  // column in diameters (W/d) means the point's own d, not the template's.
  std::vector<std::string> out = set;
  bool any_in_diameters = false;
  for (std::size_t c = 0; c < design.size(); ++c) {
    if (design[c].in_diameters) any_in_diameters = true;
    else out.push_back(design[c].key + "=" + points[i].design[c]);
  }
  if (!any_in_diameters) return out;
  const double d_mm = load_scenario(scenario, out).def.particles.diameter_mm;
  for (std::size_t c = 0; c < design.size(); ++c)
    if (design[c].in_diameters)
      out.push_back(design[c].key + "=" + number_text(std::stod(points[i].design[c]) * d_mm));
  return out;
}

LoadedScenario DataFile::point_scenario(std::size_t i, const std::vector<std::string>& extra) const {
  std::vector<std::string> o = point_overrides(i);
  o.insert(o.end(), extra.begin(), extra.end());
  return load_scenario(scenario, o);
}

std::string DataFile::point_label(std::size_t i) const {
  std::string s;
  for (std::size_t c = 0; c < design.size(); ++c) s += (c ? ", " : "") + design[c].column + "=" + points[i].design[c];
  if (mixed_observables()) s += std::string(": ") + to_string(points[i].observable);
  return s;
}

std::size_t DataFile::distinct_runs_per_replicate() const {
  std::set<std::vector<std::string>> seen;
  for (const DataPoint& p : points) seen.insert(p.design);
  return seen.size();
}

bool DataFile::mixed_observables() const {
  for (const DataPoint& p : points)
    if (p.observable != points.front().observable) return true;
  return false;
}

std::string DataFile::observables_text() const {
  std::vector<std::pair<std::string, int>> seen;  // "kind (scale)", points; in order of appearance
  for (const DataPoint& p : points) {
    const std::string k = fmt::format("{} ({})", to_string(p.observable), p.scale == FitScale::log ? "log" : "linear");
    auto it = std::find_if(seen.begin(), seen.end(), [&](const auto& e) { return e.first == k; });
    if (it == seen.end()) seen.emplace_back(k, 1);
    else ++it->second;
  }
  if (seen.size() == 1) return seen.front().first;
  std::string s;
  for (const auto& [k, n] : seen) s += fmt::format("{}{} at {} points", s.empty() ? "" : ", ", k, n);
  return s;
}

double DataFile::fit_value(std::size_t i) const { return to_fit_scale(points[i].scale, points[i].value); }

SeFloor DataFile::floor_of(ObservableKind k) const {
  for (const auto& [kind, floor] : floors)
    if (kind == k) return floor;
  return {floor_relative, 0.0};
}

double DataFile::fit_se(std::size_t i) const {
  return points[i].scale == FitScale::log ? points[i].se / points[i].value : points[i].se;
}

std::size_t DataFile::fitted_count() const {
  std::size_t n = 0;
  for (const DataPoint& p : points) n += p.held_out ? 0 : 1;
  return n;
}

std::vector<bool> DataFile::held_out_flags() const {
  std::vector<bool> out;
  for (const DataPoint& p : points) out.push_back(p.held_out);
  return out;
}

}  // namespace gapflow

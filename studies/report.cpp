// Report: the [report] options, grouping stored runs into points, and make_report().
#include "studies/report.hpp"

#include "common/text_file.hpp"
#include "common/toml_parse.hpp"

#include "common/scenario_loader.hpp"

#include <fmt/format.h>
#include <toml++/toml.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <set>
#include <sstream>

namespace gapflow {

const char* to_string(ReportKind k) {
  switch (k) {
    case ReportKind::flow_vs_gap:
      return "flow_vs_gap";
    case ReportKind::flow_vs_distance:
      return "flow_vs_distance";
    case ReportKind::clogging:
      return "clogging";
    case ReportKind::models:
      return "models";
    case ReportKind::screen_confirm:
      return "screen_confirm";
  }
  return "?";
}

namespace {

// ---------------------------------------------------------------- study file

SourceLocation where_of(const std::string& source, const toml::node& n) {
  const auto& b = n.source().begin;
  return {source, static_cast<int>(std::max(1u, b.line)), static_cast<int>(std::max(1u, b.column))};
}

std::string node_text(const toml::node& n) {
  std::ostringstream os;
  if (n.is_string()) return "\"" + n.as_string()->get() + "\"";
  n.visit([&](auto&& v) { os << v; });
  return os.str();
}

const std::vector<std::string> kReportKeys{"kind", "baseline", "j", "fit_w_min", "fit_w_max", "pairing"};

std::string read_text(const toml::table& t, const std::string& source, const char* key) {
  const toml::node* n = t.get(key);
  if (!n->is_string())
    throw ScenarioError(where_of(source, *n), std::string("report.") + key, node_text(*n), "must be a string");
  return n->as_string()->get();
}

double read_number(const toml::table& t, const std::string& source, const char* key) {
  const toml::node* n = t.get(key);
  const std::optional<double> v = number_value(*n);
  if (!v || !std::isfinite(*v))
    throw ScenarioError(where_of(source, *n), std::string("report.") + key, node_text(*n), "must be a finite number");
  return *v;
}

template <class E>
E choose(const toml::node& n, const std::string& source, const char* key,
         const std::vector<std::pair<std::string, E>>& choices) {
  std::string allowed;
  for (const auto& [name, e] : choices) {
    if (n.is_string() && n.as_string()->get() == name) return e;
    allowed += (allowed.empty() ? "\"" : ", \"") + name + "\"";
  }
  throw ScenarioError(where_of(source, n), std::string("report.") + key, node_text(n), "must be one of " + allowed);
}

// kind = "x" or kind = ["x", "y"].
std::vector<ReportKind> read_kinds(const toml::node& n, const std::string& source) {
  const std::vector<std::pair<std::string, ReportKind>> choices{{"flow_vs_gap", ReportKind::flow_vs_gap},
                                                                {"flow_vs_distance", ReportKind::flow_vs_distance},
                                                                {"clogging", ReportKind::clogging},
                                                                {"models", ReportKind::models},
                                                                {"screen_confirm", ReportKind::screen_confirm}};
  std::vector<ReportKind> out;
  if (const toml::array* a = n.as_array()) {
    for (const toml::node& k : *a) out.push_back(choose(k, source, "kind", choices));
  } else {
    out.push_back(choose(n, source, "kind", choices));
  }
  return out;
}

ReportOptions read_report_table(const toml::table& t, const std::string& source) {
  for (const auto& [k, n] : t)
    if (std::find(kReportKeys.begin(), kReportKeys.end(), k.str()) == kReportKeys.end())
      throw ScenarioError(where_of(source, n), "report." + std::string(k.str()), node_text(n),
                          "unknown key; allowed in [report]: kind, baseline, "
                          "j, fit_w_min, fit_w_max, pairing");
  ReportOptions o;
  if (const toml::node* k = t.get("kind")) o.kinds = read_kinds(*k, source);
  if (t.get("baseline")) o.baseline = read_text(t, source, "baseline");
  if (const toml::node* j = t.get("j"))
    o.j = choose<JKind>(*j, source, "j", {{option_name(JKind::paper), JKind::paper}, {option_name(JKind::flowing), JKind::flowing},
                                          {option_name(JKind::mid), JKind::mid}});
  if (const toml::node* q = t.get("pairing"))
    o.pairing = choose<Pairing>(*q, source, "pairing", {{"unpaired", Pairing::never}, {"paired", Pairing::when_exact}});
  if (t.get("fit_w_min")) o.fit_w_min = read_number(t, source, "fit_w_min");
  if (t.get("fit_w_max")) o.fit_w_max = read_number(t, source, "fit_w_max");
  if (o.fit_w_max < o.fit_w_min)
    throw ScenarioError(where_of(source, *t.get("fit_w_max")), "report.fit_w_max", node_text(*t.get("fit_w_max")),
                        "must be >= fit_w_min");
  return o;
}

// [study] keys the report shows; anything malformed is left to the study loader.
void read_study_table(const toml::table& t, StudyInfo& info) {
  info.name = t["name"].value_or(std::string());
  info.description = t["description"].value_or(std::string());
  if (auto r = t["replicates"].value<std::int64_t>()) info.replicates = static_cast<int>(*r);
  if (const toml::array* m = t["models"].as_array())
    for (const toml::node& n : *m)
      if (auto s = n.value<std::string>()) info.models.push_back(*s);
  if (info.models.empty()) info.models.push_back("2d");  // the study loader's default
}

}  // namespace

StudyInfo parse_study_info(std::string_view text, std::string_view source_name) {
  const std::string source(source_name);
  toml::table doc = parse_toml_located(text, source);
  StudyInfo info;
  if (const toml::table* s = doc["study"].as_table()) read_study_table(*s, info);
  if (const toml::array* series = doc["series"].as_array())
    for (const toml::node& n : *series)
      if (const toml::table* t = n.as_table())
        if (auto label = (*t)["label"].value<std::string>()) info.series_order.push_back(*label);
  if (const toml::node* r = doc.get("report")) {
    if (!r->is_table()) throw ScenarioError(where_of(source, *r), "report", node_text(*r), "must be a table [report]");
    info.report = read_report_table(*r->as_table(), source);
  }
  info.screen = doc.contains("screen");
  if (info.screen && info.report.baseline.empty()) info.report.baseline = kScreenBaseline;  // its baselines' series
  return info;
}

StudyInfo read_study_info(const std::filesystem::path& file) {
  StudyInfo info = parse_study_info(read_input_file(file, "study file"), file.string());
  info.file = file;
  return info;
}

// ---------------------------------------------------------------- axes_json

namespace {

// A reader for the flat objects the job expander writes: {"key":literal,...},
// literals being JSON numbers, strings (simple escapes) or booleans.
class FlatJson {
 public:
  explicit FlatJson(std::string_view s) : s_(s) {}

  std::vector<AxisEntry> parse() {
    std::vector<AxisEntry> out;
    expect('{');
    if (peek() == '}') return ++i_, out;
    for (;;) {
      AxisEntry e;
      e.key = string();
      expect(':');
      value(e);
      out.push_back(std::move(e));
      if (peek() == ',') {
        ++i_;
        continue;
      }
      expect('}');
      return out;
    }
  }

 private:
  char peek() {
    while (i_ < s_.size() && std::isspace(static_cast<unsigned char>(s_[i_]))) ++i_;
    if (i_ >= s_.size()) fail("unexpected end");
    return s_[i_];
  }
  void expect(char c) {
    if (peek() != c) fail(fmt::format("expected '{}'", c));
    ++i_;
  }
  std::string string() {
    expect('"');
    std::string out;
    while (i_ < s_.size() && s_[i_] != '"') {
      if (s_[i_] == '\\' && i_ + 1 < s_.size()) ++i_;  // \" and \\ : the escaped character itself
      out += s_[i_++];
    }
    expect('"');
    return out;
  }
  void value(AxisEntry& e) {
    if (peek() == '"') {
      e.text = string();
      return;
    }
    const std::size_t start = i_;
    while (i_ < s_.size() && s_[i_] != ',' && s_[i_] != '}') ++i_;
    std::string lit(s_.substr(start, i_ - start));
    lit.erase(lit.find_last_not_of(" \t\r\n") + 1);
    e.text = lit;
    if (lit == "true" || lit == "false") return;
    try {
      std::size_t used = 0;
      e.number = std::stod(lit, &used);
      if (used != lit.size()) fail("bad number '" + lit + "'");
    } catch (const std::logic_error&) {
      fail("bad value '" + lit + "'");
    }
  }
  [[noreturn]] void fail(const std::string& what) const {
    throw std::runtime_error(fmt::format("axes_json '{}': {} at offset {}", s_, what, i_));
  }

  std::string_view s_;
  std::size_t i_ = 0;
};

}  // namespace

std::vector<AxisEntry> parse_axes_json(std::string_view json) {
  if (json.empty()) return {};
  return FlatJson(json).parse();
}

const AxisEntry* ReportPoint::axis(std::string_view key) const {
  for (const AxisEntry& a : axes)
    if (a.key == key) return &a;
  return nullptr;
}

// ---------------------------------------------------------------- collection

namespace {

// series, model, axes (JSON): a point is what its runs were run at, not its index in the grid;
// a sweep that gained or lost a value renumbers the grid, and runs stored before keep the old index.
using PointKey = std::tuple<std::string, std::string, std::string>;

std::vector<std::string> series_in_order(const std::vector<StoredRun>& runs, const StudyInfo& info) {
  std::set<std::string> present;
  for (const StoredRun& r : runs) present.insert(r.id.series);
  std::vector<std::string> order;
  for (const std::string& s : info.series_order)
    if (present.erase(s)) order.push_back(s);
  order.insert(order.end(), present.begin(),
               present.end());  // not in the study file: alphabetical
  return order;
}

void add_totals(const std::vector<StoredRun>& runs, ReportData& d) {
  std::set<std::string> models;
  for (const StoredRun& r : runs) {
    d.total_wall_s += r.record.wall_time_s;
    d.total_sim_s += r.record.sim_time_s;
    d.code_versions[r.code_version] += 1;
    models.insert(r.id.model);
    if (d.first_finished.empty() || r.finished_at < d.first_finished) d.first_finished = r.finished_at;
    if (r.finished_at > d.last_finished) d.last_finished = r.finished_at;
  }
  d.n_runs = runs.size();
  d.models.assign(models.begin(), models.end());
}

ReportPoint make_point(const std::vector<const StoredRun*>& group, const AnalysisOptions& opt) {
  ReportPoint p;
  const JobIdentity& id = group.front()->id;
  p.series = id.series, p.model = id.model, p.point = id.point, p.point_label = id.point_label;
  p.axes = parse_axes_json(id.axes_json);
  p.d_mm = group.front()->record.diameter_m * 1e3;
  std::vector<RunRecord> records;
  for (const StoredRun* r : group) records.push_back(r->record);
  p.stats = analyze_point(records, opt);
  p.steady = steady_point_statistics(records);
  return p;
}

void compare_with_baseline(ReportData& d, const AnalysisOptions& opt) {
  if (d.study.report.baseline.empty()) return;
  for (ReportPoint& p : d.points) {
    if (is_baseline(d, p)) continue;
    const ReportPoint* b = baseline_for(d, p);
    if (!b) continue;
    p.vs_baseline = compare_to_baseline(p.stats, b->stats, d.study.report.j, opt.bootstrap, d.study.report.pairing);
    p.baseline_label = b->series + (b->point_label.empty() ? "" : " " + b->point_label);
  }
}

}  // namespace

ReportData collect_report_data(const std::vector<StoredRun>& runs, StudyInfo info, const AnalysisOptions& opt) {
  ReportData d;
  if (info.name.empty() && !runs.empty()) info.name = runs.front().id.study;
  d.study = std::move(info);
  add_totals(runs, d);
  std::map<PointKey, std::vector<const StoredRun*>> groups;
  std::map<PointKey, int> index;  // the smallest grid index the point's runs were stored under
  for (const StoredRun& r : runs) {
    const PointKey k{r.id.series, r.id.model, r.id.axes_json};
    groups[k].push_back(&r);
    const auto [it, fresh] = index.emplace(k, r.id.point);
    if (!fresh) it->second = std::min(it->second, r.id.point);
  }
  std::map<std::string, std::size_t> rank;
  for (const std::string& s : series_in_order(runs, d.study)) rank.emplace(s, rank.size());
  std::vector<PointKey> keys;
  for (const auto& [k, g] : groups) keys.push_back(k);
  std::stable_sort(keys.begin(), keys.end(), [&](const PointKey& a, const PointKey& b) {
    return std::tuple(rank[std::get<0>(a)], index[a]) < std::tuple(rank[std::get<0>(b)], index[b]);
  });
  std::set<std::string> seen_axes;
  for (const PointKey& k : keys) {
    const auto& g = groups[k];
    d.points.push_back(make_point(g, opt));
    d.points.back().point = index[k];
    for (const AxisEntry& a : d.points.back().axes)
      if (seen_axes.insert(a.key).second) d.axis_keys.push_back(a.key);
    d.min_replicates = d.min_replicates == 0 ? g.size() : std::min(d.min_replicates, g.size());
    d.max_replicates = std::max(d.max_replicates, g.size());
  }
  compare_with_baseline(d, opt);
  return d;
}

bool is_baseline(const ReportData& data, const ReportPoint& p) {
  return !data.study.report.baseline.empty() && p.series == data.study.report.baseline;
}

const ReportPoint* baseline_for(const ReportData& data, const ReportPoint& p) {
  std::vector<const ReportPoint*> same_model;
  for (const ReportPoint& b : data.points)
    if (is_baseline(data, b) && b.model == p.model) same_model.push_back(&b);
  if (same_model.size() == 1) return same_model.front();
  // Several reference points (e.g. a baseline swept over the gap): the one with the same W/d.
  for (const ReportPoint* b : same_model)
    if (std::abs(b->stats.w_over_d - p.stats.w_over_d) <= 1e-9 * std::max(1.0, std::abs(p.stats.w_over_d))) return b;
  return nullptr;
}


MeanCI mean_ci(const Summary& s) {
  MeanCI m;
  m.n = s.n;
  if (s.n == 0) return m;  // summarize() gives mean 0 here: that must not read as J = 0
  m.mean = s.mean;
  if (s.n >= 2) m.lo = s.lo(), m.hi = s.hi();
  return m;
}

MeanCI j_star(const PointStatistics& s, JKind k) { return mean_ci(j_stats(s, k).t).scaled(s.j_star_factor); }

XAxis x_axis_of(const ReportData& data, const std::string& series) {
  for (const ReportPoint& p : data.points) {
    if (p.series != series) continue;
    if (p.axis("bottleneck.gap_mm")) return {"W/d", "bottleneck.gap_mm"};
    if (p.axis("obstruction.distance_mm")) return {"D/d", "obstruction.distance_mm"};
    for (const AxisEntry& a : p.axes)
      if (!std::isnan(a.number)) return {a.key, a.key};
    return {};
  }
  return {};
}

double x_value(const ReportPoint& p, const XAxis& x) {
  if (x.name == "W/d") return p.stats.w_over_d;
  if (x.name == "D/d") return p.stats.distance_over_d;
  const AxisEntry* a = p.axis(x.key);
  return a ? a->number : kNaN;
}

std::vector<const ReportPoint*> points_of(const ReportData& data, const std::string& series, const std::string& model) {
  std::vector<const ReportPoint*> out;
  for (const ReportPoint& p : data.points)
    if (p.series == series && p.model == model) out.push_back(&p);
  return out;
}

const ReportPoint* best_point(const std::vector<const ReportPoint*>& points, JKind j) {
  const ReportPoint* best = nullptr;
  for (const ReportPoint* p : points) {
    const MeanCI m = mean_ci(j_stats(p->stats, j).t);
    const bool complete = m.n > 0 && m.n == p->stats.n_runs;
    if (complete && (!best || m.mean > mean_ci(j_stats(best->stats, j).t).mean)) best = p;
  }
  return best;
}

std::vector<std::pair<std::string, std::string>> series_models(const ReportData& data) {
  std::vector<std::pair<std::string, std::string>> out;
  for (const ReportPoint& p : data.points) {
    auto k = std::make_pair(p.series, p.model);
    if (std::find(out.begin(), out.end(), k) == out.end()) out.push_back(k);
  }
  return out;
}

std::vector<ExperimentSection> experiment_sections(const ReportData& data, const ReportOptions& opt) {
  std::vector<ExperimentSection> out;
  for (ReportKind k : opt.kinds) {
    switch (k) {
      case ReportKind::flow_vs_gap:
        out.push_back(flow_vs_gap_section(data, opt));
        break;
      case ReportKind::flow_vs_distance:
        out.push_back(flow_vs_distance_section(data, opt));
        break;
      case ReportKind::clogging:
        out.push_back(clogging_section(data, opt));
        break;
      case ReportKind::models:
        // The screen -> confirm section holds the 2D/3D comparison already: once is enough.
        if (std::find(opt.kinds.begin(), opt.kinds.end(), ReportKind::screen_confirm) == opt.kinds.end())
          out.push_back(models_section(data, opt));
        break;
      case ReportKind::screen_confirm:
        out.push_back(screen_confirm_section(data, opt));
        break;
    }
  }
  return out;
}

}  // namespace gapflow

// Report plots: which figures to draw (as a JSON spec for
// studies/plot_study.py) and running Python.
#include "studies/report.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include "common/json_text.hpp"

#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>

extern char** environ;

#ifndef GAPFLOW_PLOT_SCRIPT
#define GAPFLOW_PLOT_SCRIPT "studies/plot_study.py"
#endif

namespace gapflow {

// ---------------------------------------------------------------- JSON spec

namespace {

std::string json_array(const std::vector<double>& v) {
  std::string out = "[";
  for (std::size_t i = 0; i < v.size(); ++i) out += (i ? ", " : "") + json_number(v[i]);
  return out + "]";
}

std::string line_json(const PlotLine& l) {
  return fmt::format(
      "{{\"label\": {}, \"group\": {}, \"model\": {}, "
      "\"style\": {}, \"x\": {}, \"y\": {}, \"ylo\": {}, "
      "\"yhi\": {}, \"xlo\": {}, \"xhi\": {}}}",
      json_string(l.label), json_string(l.group.empty() ? l.label : l.group), json_string(l.model),
      json_string(l.style), json_array(l.x), json_array(l.y), json_array(l.ylo), json_array(l.yhi), json_array(l.xlo),
      json_array(l.xhi));
}

std::string band_json(const PlotBand& b) {
  return fmt::format("{{\"label\": {}, \"model\": {}, \"y\": {}, \"lo\": {}, \"hi\": {}}}", json_string(b.label),
                     json_string(b.model), json_number(b.y), json_number(b.lo), json_number(b.hi));
}

template <class T, class F>
std::string list_json(const std::vector<T>& items, F&& one, const char* indent) {
  std::string out = "[";
  for (std::size_t i = 0; i < items.size(); ++i) out += (i ? ",\n" : "\n") + std::string(indent) + one(items[i]);
  return out + "]";
}

}  // namespace

std::string plot_spec_json(const std::vector<PlotFigure>& figures) {
  auto figure = [](const PlotFigure& f) {
    return fmt::format(
        "{{\"file\": {}, \"title\": {}, \"xlabel\": {}, "
        "\"ylabel\": {}, \"identity_line\": {},\n"
        "   \"lines\": {},\n   \"bands\": {}}}",
        json_string(f.file), json_string(f.title), json_string(f.xlabel), json_string(f.ylabel),
        f.identity_line ? "true" : "false", list_json(f.lines, line_json, "    "),
        list_json(f.bands, band_json, "    "));
  };
  return "{\"figures\": " + list_json(figures, figure, "  ") + "}\n";
}

// ---------------------------------------------------------------- generic figures

namespace {

// "W/d" -> "W_over_d"; any other character that is not a letter, digit or '_' -> '_'.
std::string x_file_part(const std::string& x_name) {
  std::string s = x_name == "W/d" ? "W_over_d" : x_name == "D/d" ? "D_over_d" : x_name;
  std::replace_if(
      s.begin(), s.end(), [](char c) { return !std::isalnum(static_cast<unsigned char>(c)) && c != '_'; }, '_');
  return s;
}

}  // namespace

std::string j_star_figure_file(const std::string& x_name) { return "j_star_vs_" + x_file_part(x_name) + ".png"; }
std::string discharge_figure_file(const std::string& x_name) {
  return "discharged_vs_" + x_file_part(x_name) + ".png";
}

namespace {

std::string model_name(const std::string& m) { return m == "2d" ? "2D" : m == "3d" ? "3D" : m; }

// An empty line named after its series and model.
PlotLine series_line(const std::string& series, const std::string& model) {
  PlotLine l;
  l.label = fmt::format("{} ({})", series, model_name(model));
  l.model = model;
  return l;
}

// The points of one series and model in increasing x.
std::vector<const ReportPoint*> points_along(const ReportData& data, const std::string& series,
                                             const std::string& model, const XAxis& x) {
  auto pts = points_of(data, series, model);
  std::stable_sort(pts.begin(), pts.end(),
                   [&](const ReportPoint* a, const ReportPoint* b) { return x_value(*a, x) < x_value(*b, x); });
  return pts;
}

PlotLine j_star_line(const ReportData& data, const std::string& series, const std::string& model, const XAxis& x,
                     JKind j) {
  PlotLine l = series_line(series, model);
  for (const ReportPoint* p : points_along(data, series, model, x)) {
    const MeanCI m = j_star(p->stats, j);
    if (m.n == 0 || !std::isfinite(x_value(*p, x))) continue;  // no run with J defined: nothing to draw
    l.x.push_back(x_value(*p, x));
    l.y.push_back(m.mean);
    l.ylo.push_back(m.lo);
    l.yhi.push_back(m.hi);
  }
  return l;
}

// One band per model whose baseline series has a single point with J defined.
std::vector<PlotBand> baseline_bands(const ReportData& data, JKind j) {
  std::vector<PlotBand> out;
  const std::string& b = data.study.report.baseline;
  if (b.empty()) return out;
  for (const std::string& model : data.models) {
    const auto pts = points_of(data, b, model);
    if (pts.size() != 1) continue;
    const MeanCI m = j_star(pts.front()->stats, j);
    if (m.n == 0) continue;
    out.push_back({fmt::format("baseline '{}' ({}), 95% CI", b, model_name(model)), model, m.mean, m.lo, m.hi});
  }
  return out;
}

// Share of the board through the gap when the run ended, against the series' x: the
// only picture of the points where no run emptied the board (no J_paper to draw).
PlotLine discharge_line(const ReportData& data, const std::string& series, const std::string& model,
                        const XAxis& x) {
  PlotLine l = series_line(series, model);
  for (const ReportPoint* p : points_along(data, series, model, x)) {
    if (!std::isfinite(p->stats.mean_passed_fraction) || !std::isfinite(x_value(*p, x))) continue;
    l.x.push_back(x_value(*p, x));
    l.y.push_back(p->stats.mean_passed_fraction);
    l.ylo.push_back(p->stats.min_passed_fraction);
    l.yhi.push_back(p->stats.max_passed_fraction);
  }
  return l;
}

// Some run ended (time limit or a permanent clog) with spheres still upstream.
bool some_board_not_emptied(const ReportData& data) {
  return std::any_of(data.points.begin(), data.points.end(), [](const ReportPoint& p) {
    return std::isfinite(p.stats.mean_passed_fraction) && p.stats.mean_passed_fraction < 1.0;
  });
}

bool has_avalanche_data(const ReportData& data) {
  return std::any_of(data.points.begin(), data.points.end(),
                     [](const ReportPoint& p) { return p.stats.avalanches.size.n_uncensored > 0; });
}

PlotFigure clogging_figure(const ReportData& data) {
  PlotFigure f{"clogging.png", "Avalanche size against the gap", "(W/d)^2", "ln(<s> + 1)", {}, {}, false};
  for (const ClogSeries& cs : analyze_clogging(data).series) {
    PlotLine l;
    l.label = fmt::format("{} ({})", cs.series, model_name(cs.model));
    l.model = cs.model;
    for (const ClogPoint& c : cs.points) {
      if (!std::isfinite(c.ln_s1)) continue;
      l.x.push_back(c.w2), l.y.push_back(c.ln_s1), l.ylo.push_back(c.ln_lo), l.yhi.push_back(c.ln_hi);
    }
    if (!l.x.empty()) f.lines.push_back(std::move(l));
  }
  return f;
}

// Share of the located clogs whose arch leans on the obstruction (clog_site), with its
// Wilson 95 % interval; points whose clogs were located by front distance alone are left out.
PlotLine clogs_on_obstruction_line(const ReportData& data, const std::string& series, const std::string& model,
                                   const XAxis& x) {
  PlotLine l = series_line(series, model);
  for (const ReportPoint* p : points_along(data, series, model, x)) {
    const ClogStatistics& c = p->stats.clogs;
    if (c.n_located == 0 || c.n_contact_not_measured > 0 || !std::isfinite(x_value(*p, x))) continue;
    const Interval w = wilson_interval(c.n_on_obstruction, c.n_located);
    l.x.push_back(x_value(*p, x));
    l.y.push_back(static_cast<double>(c.n_on_obstruction) / static_cast<double>(c.n_located));
    l.ylo.push_back(w.lo);
    l.yhi.push_back(w.hi);
  }
  return l;
}

bool some_clog_on_obstruction(const ReportData& data) {
  return std::any_of(data.points.begin(), data.points.end(),
                     [](const ReportPoint& p) { return p.stats.clogs.n_on_obstruction > 0; });
}

// One figure per swept axis (made by make_figure(x) when first needed), each series and model
// with a swept axis adding line_of(series, model, x) to its axis' figure.
template <class MakeFigure, class LineOf>
void add_figures_per_axis(const ReportData& data, std::vector<PlotFigure>& figures, MakeFigure&& make_figure,
                          LineOf&& line_of) {
  const auto first = static_cast<std::ptrdiff_t>(figures.size());
  for (const auto& [series, model] : series_models(data)) {
    const XAxis x = x_axis_of(data, series);
    if (!x.valid()) continue;  // a single point without a swept value: in the tables only
    PlotFigure fresh = make_figure(x);
    auto it = std::find_if(figures.begin() + first, figures.end(),
                           [&](const PlotFigure& f) { return f.file == fresh.file; });
    if (it == figures.end()) {
      figures.push_back(std::move(fresh));
      it = figures.end() - 1;
    }
    PlotLine l = line_of(series, model, x);
    if (!l.x.empty()) it->lines.push_back(std::move(l));
  }
}

}  // namespace

std::vector<PlotFigure> generic_figures(const ReportData& data, JKind j) {
  std::vector<PlotFigure> figures;
  const std::vector<PlotBand> bands = baseline_bands(data, j);
  add_figures_per_axis(
      data, figures,
      [&](const XAxis& x) {
        return PlotFigure{j_star_figure_file(x.name),
                          fmt::format("{}* = J sqrt(d/g) against {}", to_string(j), x.name),
                          x.name,
                          fmt::format("{}*  (mean, 95% CI)", to_string(j)),
                          {},
                          bands,
                          false};
      },
      [&](const std::string& series, const std::string& model, const XAxis& x) {
        return j_star_line(data, series, model, x, j);
      });
  if (some_board_not_emptied(data))
    add_figures_per_axis(
        data, figures,
        [](const XAxis& x) {
          return PlotFigure{discharge_figure_file(x.name),
                            fmt::format("Share of the spheres through the gap when the run ended, against {}", x.name),
                            x.name,
                            "passed / N  (mean; bars: lowest and highest run)",
                            {},
                            {},
                            false};
        },
        [&](const std::string& series, const std::string& model, const XAxis& x) {
          return discharge_line(data, series, model, x);
        });
  if (some_clog_on_obstruction(data))
    add_figures_per_axis(
        data, figures,
        [](const XAxis& x) {
          return PlotFigure{"clogs_on_obstruction_vs_" + x_file_part(x.name) + ".png",
                            fmt::format("Share of the located clogs whose arch leans on the obstruction, against {}",
                                        x.name),
                            x.name,
                            "on the obstruction / located  (95% Wilson)",
                            {},
                            {},
                            false};
        },
        [&](const std::string& series, const std::string& model, const XAxis& x) {
          return clogs_on_obstruction_line(data, series, model, x);
        });
  if (has_avalanche_data(data)) figures.push_back(clogging_figure(data));
  return figures;
}

// ---------------------------------------------------------------- running Python

int run_program(const std::vector<std::string>& argv, const std::filesystem::path& log) {
  std::vector<std::string> args = argv;
  std::vector<char*> c_args;
  for (std::string& a : args) c_args.push_back(a.data());
  c_args.push_back(nullptr);
  posix_spawn_file_actions_t fa;
  posix_spawn_file_actions_init(&fa);
  const std::string target = log.empty() ? "/dev/null" : log.string();
  posix_spawn_file_actions_addopen(&fa, 1, target.c_str(), O_WRONLY | O_CREAT | O_APPEND, 0644);
  posix_spawn_file_actions_adddup2(&fa, 1, 2);
  pid_t pid = -1;
  const int rc = posix_spawnp(&pid, c_args[0], &fa, nullptr, c_args.data(), environ);
  posix_spawn_file_actions_destroy(&fa);
  if (rc != 0) return -1;
  int status = 0;
  if (waitpid(pid, &status, 0) != pid) return -1;
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

std::optional<std::string> find_python_with_matplotlib() {
  std::vector<std::string> candidates;
  if (const char* env = std::getenv("GAPFLOW_PYTHON"); env && *env) candidates.push_back(env);
  // A python3 first on PATH (pyenv, venv) may lack matplotlib while Debian's has it.
  candidates.insert(candidates.end(), {"python3", "/usr/bin/python3"});
  for (const std::string& c : candidates)
    if (run_program({c, "-c", "import matplotlib"}, {}) == 0) return c;
  return std::nullopt;
}

std::filesystem::path plot_script_path() {
  if (const char* env = std::getenv("GAPFLOW_PLOT_SCRIPT"); env && *env) return env;
  return GAPFLOW_PLOT_SCRIPT;
}

}  // namespace gapflow

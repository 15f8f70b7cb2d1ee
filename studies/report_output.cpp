// Report output: report.md and make_report(), which writes every file of a report.
#include "studies/report.hpp"

#include "studies/report_snapshots.hpp"

#include "common/text_file.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <fstream>
#include <functional>
#include <ostream>
#include <set>

namespace gapflow {

namespace fs = std::filesystem;

namespace {

std::string shell_quote(const std::string& s) {
  if (!s.empty() && s.find_first_not_of("abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ"
                                        "0123456789/._-+=:") == std::string::npos)
    return s;
  std::string q = "'";
  for (char c : s) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return q + "'";
}

std::string hours(double s) { return fmt::format("{} s ({} h)", fmt_num(s, 4), fmt_num(s / 3600.0, 3)); }

std::string joined(const std::vector<std::string>& v) {
  std::string out;
  for (const std::string& s : v) out += (out.empty() ? "" : ", ") + s;
  return out.empty() ? "none" : out;
}

std::vector<std::string> series_labels(const ReportData& d) {
  std::vector<std::string> out;
  for (const ReportPoint& p : d.points)
    if (std::find(out.begin(), out.end(), p.series) == out.end()) out.push_back(p.series);
  return out;
}

std::string study_file_text(const StudyInfo& s) {
  if (s.file.empty()) return " (no study file given)";
  if (s.recorded_at.empty()) return fmt::format(", file `{}`", s.file.string());
  return fmt::format(", file `{}` (the copy recorded in the store at {})", s.file.string(), s.recorded_at);
}

std::string what_was_run(const ReportData& d) {
  const StudyInfo& s = d.study;
  std::string versions;
  for (const auto& [v, n] : d.code_versions)
    versions += fmt::format("{}`{}` ({} runs)", versions.empty() ? "" : ", ", v, n);
  std::string out = "## What was run\n\n";
  out += fmt::format("- study: `{}`{}\n", s.name, study_file_text(s));
  out += fmt::format("- runs: {} in {} points (series x model x point)\n", d.n_runs, d.points.size());
  out += fmt::format("- series: {}\n", joined(series_labels(d)));
  out += fmt::format("- models in the store: {}{}\n", joined(d.models),
                     s.models.empty() ? "" : " (study file: " + joined(s.models) + ")");
  out += fmt::format("- replicates per point and model: {}{}\n",
                     d.min_replicates == d.max_replicates ? fmt::format("{}", d.min_replicates)
                                                          : fmt::format("{}-{}", d.min_replicates, d.max_replicates),
                     s.replicates ? fmt::format(" (study file: {})", *s.replicates) : "");
  out += fmt::format("- code version(s): {}\n", versions.empty() ? "none" : versions);
  out += fmt::format("- total wall time (sum over runs): {}; simulated time: {}\n", hours(d.total_wall_s),
                     hours(d.total_sim_s));
  out += fmt::format("- runs finished between {} and {} (UTC)\n", d.first_finished, d.last_finished);
  std::vector<std::string> kinds;
  for (ReportKind k : s.report.kinds) kinds.push_back(to_string(k));
  out += fmt::format(
      "- flow rate used for J* and comparisons: {}; baseline: {}; analyses: "
      "{}\n\n",
      to_string(s.report.j), s.report.baseline.empty() ? "none" : "'" + s.report.baseline + "'",
      kinds.empty() ? "none (generic outputs only)" : joined(kinds));
  return out;
}

std::string figure_links(const std::vector<PlotFigure>& figures, const std::vector<std::string>& pngs) {
  std::string out;
  for (const PlotFigure& f : figures)
    if (std::find(pngs.begin(), pngs.end(), f.file) != pngs.end()) out += fmt::format("![{}]({})\n\n", f.title, f.file);
  return out;
}

}  // namespace

std::string render_report_markdown(const MarkdownInput& in) {
  const ReportData& d = *in.data;
  std::string out = fmt::format("# Study report: {}\n\n", d.study.name);
  if (!d.study.description.empty()) out += d.study.description + "\n\n";
  out += what_was_run(d);
  if (!in.compare_note.empty()) out += in.compare_note + "\n\n";
  out += "## Results by series and model\n\n";
  out +=
      "The report's flow rate three ways, side by side: mean with its percentile "
      "bootstrap 95 % interval over runs (it under-covers with 2-3 runs: the verdicts "
      "also need Welch's test), median, and the paper's rule (mean after dropping runs "
      "beyond 2 sigma; how many were dropped). Other means with Student-t 95 % "
      "intervals; J* = J sqrt(d/g), g = 9.81 m/s^2; <s>: mean avalanche size "
      "(censoring-aware); clogs: how many (no crossing for run.clog_timeout_s), and "
      "where they formed when that was measured (at detection, from the front: the "
      "spheres with a free line of sight to the gap line): on the obstruction (a "
      "chain of touching front spheres links it to a wall and none links the two "
      "walls without it: the flow stopped between obstruction and walls), else at "
      "the gap (a sphere within W/2 + d of the gap centre: an arch across the gap), "
      "else upstream (the gap's mouth had run empty); "
      "n/a: undefined (e.g. J_paper when no run emptied the "
      "board). Every statistic (decomposition included) is in points.csv.\n\n";
  for (const TextTable& t : in.tables) out += render_markdown(t) + "\n";
  const std::string links = figure_links(in.figures, in.pngs);
  if (!links.empty() || !in.plot_warning.empty()) out += "## Plots\n\n";
  if (!in.plot_warning.empty()) out += "*No plots: " + in.plot_warning + "*\n\n";
  out += links;
  out += in.snapshots;
  for (const ExperimentSection& e : in.experiments) {
    out += "## Analysis: " + e.title + "\n\n";
    for (const std::string& p : e.paragraphs) out += p + "\n\n";
    for (const TextTable& t : e.tables) out += render_markdown(t) + "\n";
    out += figure_links(e.figures, in.pngs);
  }
  out += "## Regenerate\n\n```sh\n" + in.command + "\n```\n";
  return out;
}

std::string regenerate_command(const ReportRequest& r) {
  std::string c = "gapflow report " + shell_quote(r.results.string());
  if (r.study) c += " --study " + shell_quote(r.study->string());
  if (r.out) c += " --out " + shell_quote(r.out->string());
  if (!r.plots) c += " --no-plots";
  if (!r.snapshots) c += " --no-snapshots";
  if (r.quick) c += " --quick";
  if (r.compare) c += " --compare " + shell_quote(r.compare->model + "=" + r.compare->results.string());
  if (r.j) c += std::string(" --j ") + option_name(*r.j);
  return c;
}

// ---------------------------------------------------------------- make_report

namespace {

fs::path store_file(const fs::path& results) {
  // Opened read-only later (StoreAccess::read): a missing or empty file is refused there, never created.
  return fs::is_directory(results) ? results / "runs.sqlite" : results;
}

std::vector<StoredRun> load_runs(const fs::path& db, const StudyInfo& info) {
  const Store store(db, StoreAccess::read);
  std::vector<StoredRun> runs = store.load();
  std::set<std::string> studies;
  for (const StoredRun& r : runs) studies.insert(r.id.study);
  std::string names;
  for (const std::string& s : studies) names += (names.empty() ? "'" : ", '") + s + "'";
  if (runs.empty()) throw std::invalid_argument("the results store " + db.string() + " holds no runs");
  if (!info.name.empty()) {
    if (!studies.count(info.name))
      throw std::invalid_argument(
          fmt::format("no runs of study '{}' in {} (it holds {})", info.name, db.string(), names));
    std::erase_if(runs, [&](const StoredRun& r) { return r.id.study != info.name; });
  } else if (studies.size() > 1) {
    throw std::invalid_argument(fmt::format("{} holds several studies ({}): give --study", db.string(), names));
  }
  return runs;
}

// --compare: the other store's runs of one model, relabelled as this study's. Refused when
// this store has runs of that model too (two sources for one point) or when the other store's
// runs of it belong to several studies (which one is meant?).
// A study's file as recorded in a store (nullptr if not recorded).
const StudyFileRecord* recorded_file(const std::vector<StudyFileRecord>& files, const std::string& study) {
  for (const StudyFileRecord& f : files)
    if (f.study == study) return &f;
  return nullptr;
}

// The note's sentence on whether the two study files fix the same settings.
std::string settings_sentence(const StudyFileRecord* own, const StudyFileRecord* other) {
  if (!own || !other) return "Whether the two study files fix the same settings was not checked (a study file is not recorded).";
  const std::vector<std::string> d = study_setting_differences(own->text, own->source, other->text, other->source);
  if (d.empty())
    return "The two study files fix the same settings for the series they share ([study] set, each series' scenario and set; "
           "[per_model] sets are one model's and not compared).";
  return fmt::format("**The two study files fix different settings** (here: {}; there: {}): {}. Differences in J between "
                     "the models may be these settings', not the models'.",
                     own->source, other->source, fmt::join(d, "; "));
}

std::vector<StoredRun> compared_runs(const ReportRequest::Compare& c, const std::vector<StoredRun>& own,
                                     const StudyFileRecord* own_file, std::string& note) {
  if (std::any_of(own.begin(), own.end(), [&](const StoredRun& r) { return r.id.model == c.model; }))
    throw std::invalid_argument(fmt::format("--compare {}=...: the study's own store already has {} runs", c.model, c.model));
  const fs::path db = store_file(c.results);
  std::vector<StoredRun> runs = Store(db, StoreAccess::read).load();
  std::erase_if(runs, [&](const StoredRun& r) { return r.id.model != c.model; });
  std::set<std::string> studies;
  for (const StoredRun& r : runs) studies.insert(r.id.study);
  if (studies.size() != 1)
    throw std::invalid_argument(fmt::format("--compare {}={}: {} holds {} runs of {} studies ({}); exactly one is needed",
                                            c.model, c.results.string(), db.string(), c.model, studies.size(),
                                            fmt::join(studies, ", ")));
  const std::vector<StudyFileRecord> other_files = Store(db, StoreAccess::read).study_files();
  note = fmt::format("The {} runs ({}) are those of study \"{}\", read from {} (`--compare`): the same series and "
                     "point grid, run by that study with its own settings; this study ran none of them. {}",
                     c.model, runs.size(), *studies.begin(), db.string(),
                     settings_sentence(own_file, recorded_file(other_files, *studies.begin())));
  const std::string name = own.front().id.study;  // load_runs left one study
  for (StoredRun& r : runs) r.id.study = name;
  return runs;
}

// Without --study: the study file recorded in the store when the study ran (its
// [report] settings), else a bare report (tables, no analyses) with a warning.
StudyInfo recorded_study_info(const fs::path& db, std::ostream& log) {
  const std::vector<StudyFileRecord> files = Store(db, StoreAccess::read).study_files();
  if (files.size() == 1) {
    const StudyFileRecord& f = files.front();
    log << fmt::format("using the study file recorded in the store: {} (recorded {})\n", f.source, f.recorded_at);
    StudyInfo info = parse_study_info(f.text, fmt::format("{} [as recorded in {}]", f.source, db.string()));
    info.file = f.source;
    info.recorded_at = f.recorded_at;
    return info;
  }
  log << fmt::format(
      "warning: {}: no baseline, no analyses, J_paper; give --study STUDY.toml\n",
      files.empty() ? "no study file given and none recorded in the store" : "the store records several study files");
  return StudyInfo{};
}

// The generic figures with every section's fitted curves drawn in.
std::vector<PlotFigure> all_figures(const ReportData& data, const std::vector<ExperimentSection>& experiments) {
  std::vector<PlotFigure> figures = generic_figures(data, data.study.report.j);
  for (PlotFigure& f : figures) {
    bool fitted = false;
    for (const ExperimentSection& e : experiments) {
      auto it = e.overlays.find(f.file);
      if (it == e.overlays.end()) continue;
      for (const PlotLine& l : it->second)
        if (!l.x.empty()) f.lines.push_back(l), fitted = true;
    }
    if (!fitted) continue;
    for (PlotLine& l : f.lines)  // joined data points would hide the fitted curves
      if (l.style == "errorbar") l.style = "markers";
  }
  return figures;
}

// Draws the figures with plot_study.py; the PNGs written, or a warning saying why none.
std::string draw(const std::vector<PlotFigure>& figures, const fs::path& dir, std::vector<std::string>& pngs) {
  if (figures.empty()) return "nothing to plot (no swept numeric axis, no avalanche data)";
  const auto python = find_python_with_matplotlib();
  if (!python)
    return "python3 with matplotlib was not found (install python3-matplotlib, "
           "or set GAPFLOW_PYTHON)";
  const fs::path script = plot_script_path();
  if (!fs::exists(script)) return "the plot script " + script.string() + " is missing (set GAPFLOW_PLOT_SCRIPT)";
  for (const PlotFigure& f : figures) fs::remove(dir / f.file);  // a stale PNG must not pass for a new one
  const fs::path log = dir / "plots.log";
  fs::remove(log);
  const int rc = run_program({*python, script.string(), (dir / "plots.json").string(), dir.string()}, log);
  for (const PlotFigure& f : figures)
    if (fs::exists(dir / f.file)) pngs.push_back(f.file);
  if (rc != 0) return fmt::format("{} failed (exit {}); its output is in {}", script.string(), rc, log.string());
  fs::remove(log);
  return pngs.size() == figures.size() ? "" : "some figures were not written";
}

// Re-runs one stored run per point class and draws it; the report's Snapshots section.
std::string report_snapshots(const ReportRequest& request, const fs::path& db, const std::vector<StoredRun>& runs,
                             const ReportData& data, ReportOutcome& o, std::ostream& log) {
  if (!request.snapshots) return snapshots_markdown({}, "not requested (--no-snapshots)");
  const std::vector<SnapshotPick> picks = choose_snapshots(data, runs);
  if (picks.empty()) return snapshots_markdown({}, "");
  std::vector<Snapshot> shots;
  try {
    const StudyDef study = study_for_snapshots(db, request.study, data.study.name, request.quick);
    shots = draw_snapshots(picks, study, runs, o.out_dir, log);
  } catch (const std::exception& e) {  // e.g. the recorded study file's scenario paths do not resolve from here
    o.snapshot_warning = fmt::format("the study's jobs could not be rebuilt: {}", e.what());
    log << "warning: no snapshots: " << o.snapshot_warning << "\n";
    return snapshots_markdown({}, o.snapshot_warning);
  }
  for (const Snapshot& s : shots)
    if (!s.file.empty()) o.snapshots.push_back(o.out_dir / s.file);
  return snapshots_markdown(shots, "");
}

void print_experiment(std::ostream& out, const ExperimentSection& e) {
  out << "\n== " << e.title << " ==\n";
  for (const std::string& p : e.paragraphs) out << p << "\n\n";
  for (const TextTable& t : e.tables) out << render_text(t) << "\n";
}

}  // namespace

ReportData load_report_data(const ReportRequest& request, std::ostream& log) {
  const fs::path db = store_file(request.results);
  const StudyInfo info = request.study ? read_study_info(*request.study) : recorded_study_info(db, log);
  return collect_report_data(load_runs(db, info), info);
}

ReportOutcome make_report(const ReportRequest& request, std::ostream& out, std::ostream& log) {
  const fs::path db = store_file(request.results);
  StudyInfo info = request.study ? read_study_info(*request.study) : recorded_study_info(db, log);
  if (request.j) info.report.j = *request.j;
  const std::vector<StoredRun> runs = load_runs(db, info);  // this store's: snapshots re-run these only
  std::string compare_note;
  std::vector<StoredRun> all = runs;
  if (request.compare) {
    // This study's file: the one given, else the one its store recorded.
    StudyFileRecord own_file;
    const std::vector<StudyFileRecord> recorded = Store(db, StoreAccess::read).study_files();
    const StudyFileRecord* own = recorded_file(recorded, info.name);
    if (request.study) {
      own_file = {info.name, request.study->string(), read_input_file(*request.study, "study file"), ""};
      own = &own_file;
    }
    const std::vector<StoredRun> other = compared_runs(*request.compare, runs, own, compare_note);
    all.insert(all.end(), other.begin(), other.end());
  }
  const ReportData data = collect_report_data(all, info);
  const ReportOptions& opt = data.study.report;
  if (!opt.baseline.empty() && std::none_of(data.points.begin(), data.points.end(),
                                            [&](const ReportPoint& p) { return p.series == opt.baseline; }))
    log << fmt::format("warning: the baseline series '{}' has no runs: no ratios\n", opt.baseline);

  ReportOutcome o;
  o.out_dir = request.out ? *request.out : (db.has_parent_path() ? db.parent_path() : fs::path("."));
  check_output_folder(o.out_dir);
  fs::create_directories(o.out_dir);
  o.n_points = data.points.size();
  o.n_runs = data.n_runs;
  o.points_csv = o.out_dir / "points.csv";
  write_file_atomically(o.points_csv, [&](std::ostream& s) { write_points_csv(s, data); });

  MarkdownInput md;
  md.data = &data;
  md.tables = point_tables(data, opt.j);
  md.command = regenerate_command(request);
  md.compare_note = compare_note;
  out << fmt::format("study '{}': {} runs, {} points\n\n", data.study.name, data.n_runs, data.points.size());
  for (const TextTable& t : md.tables) out << render_text(t) << "\n";
  md.experiments = experiment_sections(data, opt);
  if (data.study.screen) md.experiments.push_back(screen_report_section(request, db, runs, o.out_dir, log));
  for (const ExperimentSection& e : md.experiments) print_experiment(out, e);

  md.figures = all_figures(data, md.experiments);
  std::vector<PlotFigure> to_draw = md.figures;
  for (const ExperimentSection& e : md.experiments) to_draw.insert(to_draw.end(), e.figures.begin(), e.figures.end());
  std::erase_if(to_draw,
                [](const PlotFigure& f) {  // e.g. J* where no run passed every particle
                  return std::all_of(f.lines.begin(), f.lines.end(), [](const PlotLine& l) { return l.x.empty(); });
                });
  write_file_atomically(o.out_dir / "plots.json", [&](std::ostream& s) { s << plot_spec_json(to_draw); });
  md.plot_warning = request.plots ? draw(to_draw, o.out_dir, md.pngs) : "not requested (--no-plots)";
  if (!md.plot_warning.empty()) log << "warning: no plots: " << md.plot_warning << "\n";
  for (const std::string& f : md.pngs) o.pngs.push_back(o.out_dir / f);
  o.plot_warning = md.plot_warning;
  md.snapshots = report_snapshots(request, db, runs, data, o, log);

  o.markdown = o.out_dir / "report.md";
  write_file_atomically(o.markdown, [&](std::ostream& s) { s << render_report_markdown(md); });
  out << fmt::format("wrote {}, {}, {} plot(s), {} snapshot(s) in {}\n", o.points_csv.filename().string(),
                     o.markdown.filename().string(), o.pngs.size(), o.snapshots.size(), o.out_dir.string());
  return o;
}

}  // namespace gapflow

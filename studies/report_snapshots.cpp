// Report snapshots: which points, which stored run, which moment; re-run and draw.
#include "studies/report_snapshots.hpp"

#include "common/text_file.hpp"
#include "studies/confirm.hpp"
#include "studies/jobs.hpp"
#include "studies/sequential.hpp"
#include "view/run_outputs.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <atomic>
#include <cctype>
#include <chrono>
#include <cmath>
#include <ctime>
#include <map>
#include <ostream>
#include <tuple>

namespace gapflow {

namespace fs = std::filesystem;

namespace {

using PointKey = std::tuple<std::string, std::string, int>;  // series, model, point

// A class before its run and moment are chosen.
struct PointClass {
  std::string cls, why;
  const ReportPoint* point = nullptr;
  bool prefer_clog = false;  // show the first clog of a run that has one
};

bool has_kind(const ReportData& d, ReportKind k) {
  const auto& kinds = d.study.report.kinds;
  return std::find(kinds.begin(), kinds.end(), k) != kinds.end();
}

std::string model_name(const std::string& m) { return m == "3d" ? "3D" : m == "2d" ? "2D" : m; }

std::string point_text(const ReportPoint& p) {
  return fmt::format("series '{}', {}, {}", p.series, p.point_label.empty() ? "single point" : p.point_label,
                     model_name(p.model));
}

// The first model of the store that has points of `series`.
std::string first_model_of(const ReportData& d, const std::string& series) {
  for (const std::string& m : d.models)
    if (!points_of(d, series, m).empty()) return m;
  return {};
}

std::vector<std::string> series_in_report_order(const ReportData& d) {
  std::vector<std::string> out;
  for (const auto& [s, m] : series_models(d))
    if (std::find(out.begin(), out.end(), s) == out.end()) out.push_back(s);
  return out;
}

std::string best_why(const ReportData& d) {
  return fmt::format("largest mean {} among its points where every run has it (the report's peak rule)",
                     to_string(d.study.report.j));
}

// The best point of `points`, or (none complete) the first, to be shown at a clog.
void add_best(std::vector<PointClass>& out, const ReportData& d, std::vector<const ReportPoint*> points,
              const std::string& cls) {
  if (points.empty()) return;
  if (const ReportPoint* best = best_point(points, d.study.report.j)) {
    out.push_back({cls, best_why(d), best, false});
    return;
  }
  out.push_back({cls, fmt::format("no point has {} in every run: its first point, where the flow stops",
                                  to_string(d.study.report.j)),
                 points.front(), true});
}

std::vector<const ReportPoint*> non_baseline_points(const ReportData& d, const std::string& model) {
  std::vector<const ReportPoint*> out;
  for (const ReportPoint& p : d.points)
    if (p.model == model && !is_baseline(d, p)) out.push_back(&p);
  return out;
}

void add_baseline(std::vector<PointClass>& out, const ReportData& d) {
  for (const ReportPoint& p : d.points)
    if (is_baseline(d, p) && p.model == d.models.front()) {
      out.push_back({"J_0 reference", fmt::format("the baseline series '{}': every J/J_0 is against it", p.series), &p,
                     false});
      return;
    }
}

void add_gap_extremes(std::vector<PointClass>& out, const ReportData& d, bool clogging) {
  const ReportPoint *narrow = nullptr, *wide = nullptr;
  for (const ReportPoint& p : d.points) {
    if (p.model != d.models.front() || std::isnan(p.stats.w_over_d)) continue;
    if (!narrow || p.stats.w_over_d < narrow->stats.w_over_d) narrow = &p;
    if (!wide || p.stats.w_over_d > wide->stats.w_over_d) wide = &p;
  }
  if (!narrow) return;
  out.push_back({fmt::format("narrowest gap, W/d = {}", fmt_num(narrow->stats.w_over_d, 3)),
                 clogging ? "the gap where clogs are most frequent: shown at its first clog, the arch coloured by state"
                          : "the smallest W/d of the sweep (first model)",
                 narrow, clogging});
  if (wide != narrow)
    out.push_back({fmt::format("widest gap, W/d = {}", fmt_num(wide->stats.w_over_d, 3)),
                   "the largest W/d of the sweep (first model)", wide, false});
}

std::vector<PointClass> point_classes(const ReportData& d) {
  std::vector<PointClass> out;
  if (d.models.empty()) return out;
  if (has_kind(d, ReportKind::screen_confirm)) {
    add_baseline(out, d);
    add_best(out, d, non_baseline_points(d, d.models.front()),
             fmt::format("best of the screen ({})", model_name(d.models.front())));
    if (d.models.size() > 1)
      add_best(out, d, non_baseline_points(d, d.models.back()),
               fmt::format("best confirmed ({})", model_name(d.models.back())));
  } else if (has_kind(d, ReportKind::flow_vs_distance)) {
    add_baseline(out, d);
    for (const std::string& s : series_in_report_order(d))
      if (s != d.study.report.baseline) add_best(out, d, points_of(d, s, first_model_of(d, s)), s + " at its best position");
  } else if (has_kind(d, ReportKind::flow_vs_gap) || has_kind(d, ReportKind::clogging)) {
    add_gap_extremes(out, d, has_kind(d, ReportKind::clogging));
  } else {
    for (const std::string& s : series_in_report_order(d))
      add_best(out, d, points_of(d, s, first_model_of(d, s)), "series " + s);
  }
  return out;
}

std::optional<double> j_of(const RunRecord& r, JKind k) {
  return k == JKind::paper ? r.j_paper : k == JKind::flowing ? r.j_flowing : r.j_mid;
}

// The replicate that stands for its point: at a clog, the first with one; else the run whose
// J is closest to the point's median (ties: the lower replicate); else the first.
const StoredRun* representative_run(const std::vector<const StoredRun*>& runs, JKind k, bool prefer_clog,
                                    std::string& why) {
  if (prefer_clog)
    for (const StoredRun* r : runs)
      if (!r->record.clogs.empty() && r->record.clogs.front().t_start <= kSnapshotMaxTimeS) {
        why = "the first replicate with a clog";
        return r;
      }
  std::vector<double> js;
  for (const StoredRun* r : runs)
    if (auto j = j_of(r->record, k)) js.push_back(*j);
  if (js.empty()) {
    why = fmt::format("the first replicate (no run has {})", to_string(k));
    return runs.front();
  }
  std::sort(js.begin(), js.end());
  const std::size_t n = js.size();
  const double median = n % 2 ? js[n / 2] : (js[n / 2 - 1] + js[n / 2]) / 2;
  const StoredRun* best = nullptr;
  for (const StoredRun* r : runs) {
    const auto j = j_of(r->record, k);
    if (j && (!best || std::abs(*j - median) < std::abs(*j_of(best->record, k) - median))) best = r;
  }
  why = fmt::format("{} {} /s, closest to the point's median {} /s", to_string(k), fmt_num(*j_of(best->record, k)),
                    fmt_num(median));
  return best;
}

// Mid-discharge: when half of the board's spheres had crossed (the start-up is over and the
// flow established, while the region above the gap and the obstruction is still full);
// in a run where fewer crossed, its median crossing. Capped at kSnapshotMaxTimeS.
void mid_discharge(SnapshotPick& p) {
  const RunRecord& r = p.run->record;
  std::vector<double> t;
  for (const Crossing& c : r.crossings) t.push_back(c.t);
  std::sort(t.begin(), t.end());
  const std::size_t half = static_cast<std::size_t>((r.particles + 1) / 2);
  if (t.empty()) {  // none crossed, or a slim store kept none (scripts/slim_store.py)
    p.t_s = std::min(r.sim_time_s / 2, kSnapshotMaxTimeS);
    p.when = r.passed > 0 ? fmt::format("half-way through the run ({} spheres crossed in it)", r.passed)
                          : "half-way through a run without crossings";
  } else if (t.size() >= half && half > 0) {
    p.t_s = t[half - 1];
    p.when = fmt::format("when {} of the {} spheres had crossed in the stored run (mid-discharge: the flow "
                         "established, the board above the gap still full)",
                         half, r.particles);
  } else {
    p.t_s = t[(t.size() - 1) / 2];
    p.when = fmt::format("at the median of the stored run's {} crossings (of {} spheres; it never emptied half)",
                         t.size(), r.particles);
  }
  if (p.t_s > kSnapshotMaxTimeS) {
    p.t_s = kSnapshotMaxTimeS;
    p.when += fmt::format("; capped at {} s to keep the re-run short", kSnapshotMaxTimeS);
  }
}

}  // namespace

std::vector<SnapshotPick> choose_snapshots(const ReportData& data, const std::vector<StoredRun>& runs) {
  std::map<PointKey, std::vector<const StoredRun*>> by_point;
  for (const StoredRun& r : runs) by_point[{r.id.series, r.id.model, r.id.point}].push_back(&r);
  for (auto& [k, v] : by_point)
    std::stable_sort(v.begin(), v.end(),
                     [](const StoredRun* a, const StoredRun* b) { return a->id.replicate < b->id.replicate; });
  std::vector<SnapshotPick> out;
  for (const PointClass& c : point_classes(data)) {
    const auto it = by_point.find({c.point->series, c.point->model, c.point->point});
    if (it == by_point.end() || it->second.empty()) continue;
    SnapshotPick p;
    p.cls = c.cls, p.why = c.why, p.point = c.point;
    p.run = representative_run(it->second, data.study.report.j, c.prefer_clog, p.run_why);
    const std::vector<Clog>& clogs = p.run->record.clogs;
    if (c.prefer_clog && !clogs.empty() && clogs.front().t_start <= kSnapshotMaxTimeS) {
      p.at_clog = true;
      p.t_s = clogs.front().t_start;
      p.when = "when its first clog was detected (run.clog_timeout_s after the last crossing), coloured by state";
    } else {
      mid_discharge(p);
    }
    out.push_back(std::move(p));
  }
  return out;
}

StudyDef study_for_snapshots(const fs::path& db, const std::optional<fs::path>& file, const std::string& study_name,
                             bool quick) {
  auto variant = [&](StudyDef study) {
    if (!quick) return study;
    if (!study.quick.present)
      throw std::invalid_argument("--quick: the study file " + study.file.string() + " has no [quick] table");
    StudyDef q = apply_quick(std::move(study));
    q.quick = {};  // applied: jobs_by_key must not thin it again
    return q;
  };
  if (file) return variant(load_study(*file));
  for (const StudyFileRecord& f : Store(db).study_files())
    if (f.study == study_name || study_name.empty())
      return variant(parse_study(f.text, f.source, fs::path(f.source).parent_path()));
  throw std::invalid_argument("no study file given (--study) and none recorded in the store");
}

namespace {

// Every job a stored run of `study` can come from, by key.
std::map<std::string, Job> jobs_by_key(const StudyDef& study, const std::vector<StoredRun>& runs) {
  std::map<std::string, Job> out;
  auto add = [&](std::vector<Job> jobs) {
    for (Job& j : jobs) out.emplace(j.id.key, std::move(j));
  };
  if (study.screen) {  // its grid has cells that do not fit and its replicates vary: the stored runs' jobs
    for (const StoredRun& r : runs)
      for (const SeriesDef& s : study.series)
        if (s.label == r.id.series && r.id.model == to_string(study.models.at(0)))
          add(point_jobs(study, s, r.id.point, study.models.at(0), r.id.replicate, r.id.replicate + 1));
    return out;
  }
  add(expand_jobs(study));
  if (study.sequential.enabled) add(expand_jobs(study, stored_replicate_counts(runs)));  // the rounds' runs too
  if (study.quick.present) add(expand_jobs(apply_quick(study)));
  if (study.confirm.enabled) add(confirm_jobs(study, rank_screened_points(study, runs)));
  return out;
}

std::string file_name(std::size_t i, const std::string& cls) {
  std::string slug;
  for (char c : cls) {
    const bool keep = std::isalnum(static_cast<unsigned char>(c));
    if (keep) slug += static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    else if (!slug.empty() && slug.back() != '-') slug += '-';
  }
  while (!slug.empty() && slug.back() == '-') slug.pop_back();
  return fmt::format("snapshot_{}_{}.png", i + 1, slug);
}

// Re-run the pick's job until its picture is drawn.
void draw_one(Snapshot& s, std::size_t i, const Job& job, const fs::path& dir, std::ostream& log) {
  const SnapshotPick& p = s.pick;
  const CompiledScenario sc = compile_job(job);
  // Snapshots are drawn at the step nearest their time; half a step later makes it the first
  // step at or after the moment (the crossing that defines it is then counted).
  const double dt = p.run->record.time_step_s;
  const double t = (p.at_clog ? p.t_s + sc.def.run.clog_timeout_s + dt : p.t_s) + dt / 2;
  RunOutputDef def;
  def.snapshot_times_s = {t};
  def.snapshot_dir = (dir / fmt::format(".snapshot-{}.tmp", i + 1)).string();
  def.view.colour_by = p.at_clog ? Colouring::state : Colouring::speed;
  def.view.title = p.cls;
  struct RemoveOnExit {  // the scratch folder goes, whatever happens to the re-run
    fs::path dir;
    ~RemoveOnExit() {
      std::error_code ignored;
      fs::remove_all(dir, ignored);
    }
  } scratch{def.snapshot_dir};
  fs::remove_all(scratch.dir);
  std::atomic<bool> stop{false};
  const auto wall0 = std::chrono::steady_clock::now();
  const std::clock_t cpu0 = std::clock();
  {
    RunOutputs outputs(sc, def);
    StepObserver observer;
    observer.after_step = [&](double now, const EngineSession& session, const GapMonitor& monitor) {
      outputs.observer().after_step(now, session, monitor);
      if (stop || outputs.written().empty()) return;
      s.t_drawn_s = now;
      s.passed_rerun = monitor.passed();
      stop = true;  // the run driver stops between steps (RunCancelled)
    };
    try {
      run_model(sc, job.model, &observer, &stop);
    } catch (const RunCancelled&) {
    }
    if (outputs.written().empty()) {
      s.problem = fmt::format("the re-run ended before t = {} s", fmt_num(t));
    } else {
      s.file = file_name(i, p.cls);
      fs::rename(outputs.written().front(), dir / s.file);
      const TopView view(sc, def.view);
      s.width = view.width(), s.height = view.height();
    }
  }
  if (crossings_stored(p.run->record))
    s.passed_stored = static_cast<int>(std::count_if(p.run->record.crossings.begin(), p.run->record.crossings.end(),
                                                   [&](const Crossing& c) { return c.t <= s.t_drawn_s; }));
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count();
  log << fmt::format("snapshot '{}': re-ran job {} ({}) to t = {:.2f} s in {:.1f} s wall, {:.1f} s CPU{}\n", p.cls,
                     job.id.key, job.id.model, s.t_drawn_s, wall, double(std::clock() - cpu0) / CLOCKS_PER_SEC,
                     !s.comparable() ? " (the store keeps no crossings)"
                     : s.matches()   ? ""
                                     : " (crossings differ from the stored run)");
}

}  // namespace

std::vector<Snapshot> draw_snapshots(const std::vector<SnapshotPick>& picks, const StudyDef& study,
                                     const std::vector<StoredRun>& runs, const fs::path& dir, std::ostream& log) {
  std::vector<Snapshot> out;
  if (picks.empty()) return out;
  const std::map<std::string, Job> jobs = jobs_by_key(study, runs);
  for (std::size_t i = 0; i < picks.size(); ++i) {
    Snapshot s;
    s.pick = picks[i];
    const auto it = jobs.find(s.pick.run->id.key);
    try {
      if (it == jobs.end())
        s.problem = fmt::format("job {} is not among the study file's jobs (the file changed since the run?)",
                                s.pick.run->id.key);
      else
        draw_one(s, i, it->second, dir, log);
    } catch (const std::exception& e) {
      s.problem = e.what();
    }
    if (!s.problem.empty()) log << fmt::format("warning: snapshot '{}' not drawn: {}\n", s.pick.cls, s.problem);
    out.push_back(std::move(s));
  }
  return out;
}

namespace {

std::string caption(const Snapshot& s) {
  const SnapshotPick& p = s.pick;
  const JobIdentity& id = p.run->id;
  std::string out = fmt::format("- **{}** ({}): {}; {}. Replicate {} ({}; study seed {}, run seed {}, job key `{}`, "
                                "code `{}`)",
                                p.cls, s.file.empty() ? "not drawn" : s.file, point_text(*p.point), p.why,
                                id.replicate, p.run_why, id.base_seed, id.run_seed, id.key, p.run->code_version);
  if (!s.problem.empty()) return out + ". Not drawn: " + s.problem + ".\n";
  out += fmt::format(", t = {:.2f} s after release, {}. ", s.t_drawn_s, p.when);
  if (!s.comparable())
    return out + fmt::format("The re-run had {} crossings by then; the store keeps no crossing times to compare "
                             "them with (a picture of the same scenario and seed). {} x {} px.\n",
                             s.passed_rerun, s.width, s.height);
  out += s.matches() ? fmt::format("The re-run had {} crossings by then, as the stored run: the picture is of that run.",
                                   s.passed_rerun)
                     : fmt::format("The re-run had {} crossings by then, the stored run {}: this code no longer "
                                   "reproduces that run exactly (a picture of the same scenario and seed).",
                                   s.passed_rerun, s.passed_stored);
  return out + fmt::format(" {} x {} px.\n", s.width, s.height);
}

}  // namespace

std::string snapshots_markdown(const std::vector<Snapshot>& shots, const std::string& warning) {
  std::string out = "## Snapshots\n\n";
  if (!warning.empty()) return out + "*No snapshots: " + warning + "*\n\n";
  if (shots.empty()) return out + "*No snapshots: no point class to show.*\n\n";
  out +=
      "One top view per point class, each a re-run of one stored run (its job rebuilt from the study file and found "
      "by its job key: the same scenario and seed) up to the moment stated, drawn as `gapflow run --snapshot-at` "
      "draws (view/top_view.hpp): spheres at their true size coloured by speed (colour bar 0-0.5 m/s) or, at a "
      "clog, by state (red: the front the gap sees). `--no-snapshots` leaves the pictures out.\n\n";
  std::string head = "|", rule = "|", row = "|";
  for (const Snapshot& s : shots) {
    if (s.file.empty()) continue;
    head += " " + s.pick.cls + " |";
    rule += " :-: |";
    row += fmt::format(" ![{}]({}) |", s.pick.cls, s.file);
  }
  if (head != "|") out += head + "\n" + rule + "\n" + row + "\n\n";
  for (const Snapshot& s : shots) out += caption(s);
  return out + "\n";
}

}  // namespace gapflow

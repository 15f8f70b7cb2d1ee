#include "app/cmd_study.hpp"

#include "app/cli_errors.hpp"
#include "common/text_file.hpp"

#include "studies/jobs.hpp"
#include "studies/confirm.hpp"
#include "studies/runner.hpp"
#include "studies/store.hpp"
#include "studies/study.hpp"

#include <CLI/CLI.hpp>
#include <fmt/format.h>

#include <atomic>
#include <csignal>
#include <fstream>
#include <iostream>
#include <map>
#include <thread>
#include <unistd.h>

namespace gapflow {

struct StudyCommands::Options {
  CLI::App* study = nullptr;
  std::string study_file, db;
  bool quick = false, dry_run = false;
  int jobs = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));

  CLI::App* export_cmd = nullptr;
  std::string export_db, table = "runs", csv = "-";
};

namespace {

constexpr int kInterrupted = 130;  // 128 + SIGINT, what shells report for Ctrl-C

// Raised by SIGINT/SIGTERM; the workers' run_model calls poll it between steps.
std::atomic<bool> g_cancel{false};
static_assert(std::atomic<bool>::is_always_lock_free, "the signal handler needs a lock-free flag");

extern "C" void on_signal(int) { g_cancel.store(true); }

// Ctrl-C cancels the study; SA_RESETHAND makes a second Ctrl-C kill at once.
class CancelOnSignal {
 public:
  CancelOnSignal() {
    struct sigaction sa {};
    sa.sa_handler = on_signal;
    sa.sa_flags = SA_RESETHAND;
    sigemptyset(&sa.sa_mask);
    sigaction(SIGINT, &sa, &old_int_);
    sigaction(SIGTERM, &sa, &old_term_);
  }
  ~CancelOnSignal() {
    sigaction(SIGINT, &old_int_, nullptr);
    sigaction(SIGTERM, &old_term_, nullptr);
  }

 private:
  struct sigaction old_int_ {}, old_term_ {};
};

// --quick has its own store: its screen may confirm other points than the full
// study's, and those must not pass for the full study's confirmation.
std::filesystem::path db_path(const StudyCommands::Options& o, const StudyDef& study) {
  if (!o.db.empty()) return o.db;
  return std::filesystem::path("results") / (o.quick ? study.name + "-quick" : study.name) / "runs.sqlite";
}

void print_dry_run(const StudyDef& study, const std::vector<Job>& jobs, const std::filesystem::path& db) {
  std::set<std::string> stored;
  if (std::filesystem::exists(db)) stored = Store(db, StoreAccess::read).keys();
  // (series, model) -> jobs, stored; in job order.
  std::vector<std::pair<std::string, std::string>> order;
  std::map<std::pair<std::string, std::string>, std::pair<int, int>> count;
  for (const Job& j : jobs) {
    auto k = std::make_pair(j.id.series, j.id.model);
    if (!count.count(k)) order.push_back(k);
    count[k].first += 1;
    count[k].second += stored.count(j.id.key) ? 1 : 0;
  }
  std::cout << fmt::format("study '{}': {} jobs ({} replicates per point and model), store {}\n", study.name,
                           jobs.size(), study.replicates, db.string());
  std::cout << fmt::format("{:24s} {:5s} {:>6s} {:>7s}\n", "series", "model", "jobs", "stored");
  int total_stored = 0;
  for (const auto& k : order) {
    std::cout << fmt::format("{:24s} {:5s} {:6d} {:7d}\n", k.first, k.second, count[k].first, count[k].second);
    total_stored += count[k].second;
  }
  std::cout << fmt::format("{:24s} {:5s} {:6d} {:7d}\n", "total", "", jobs.size(), total_stored);
}

// Screen -> confirm: rank the screened points and run the best again with the confirming model.
RunnerSummary run_confirm_stage(const StudyDef& study, Store& store, const RunnerOptions& options,
                                RunnerSummary screen) {
  const std::vector<RankedPoint> ranked = rank_screened_points(study, store.load(study.name));
  std::cerr << fmt::format("screen ranking by mean J_{} (best first; the top {} are confirmed with {}):\n",
                           study.confirm.rank_by, study.confirm.top, to_string(study.confirm.model));
  for (size_t i = 0; i < ranked.size() && i < static_cast<size_t>(study.confirm.top) + 5; ++i)
    std::cerr << fmt::format("  {:2d}. {:12s} {:40s} J = {:8.2f} /s ({} runs)\n", i + 1, ranked[i].series,
                             ranked[i].point_label, ranked[i].mean_j, ranked[i].runs);
  const RunnerSummary c = run_jobs(confirm_jobs(study, ranked), store, options);
  screen.total += c.total;
  screen.already_stored += c.already_stored;
  screen.done_now += c.done_now;
  screen.failed.insert(screen.failed.end(), c.failed.begin(), c.failed.end());
  screen.cancelled = c.cancelled;
  return screen;
}

int cmd_study(const StudyCommands::Options& o) {
  StudyDef study = load_study(o.study_file);
  if (o.quick && !study.quick.present)  // silently running the full study would be no quick look
    throw ScenarioError({o.study_file, 0, 0}, "", "",
                        "this study has no [quick] table, so no quick variant: run it without --quick, "
                        "or add [quick] with replicates / models / thin");
  if (o.quick) study = apply_quick(std::move(study));
  const std::vector<Job> jobs = expand_jobs(study);  // every scenario validated before anything runs
  const std::filesystem::path db = db_path(o, study);
  if (o.dry_run) {
    print_dry_run(study, jobs, db);
    return 0;
  }
  Store store(db, StoreAccess::exclusive);  // a second study on this store refuses here
  // The report reads the study's [report] settings from the store (gapflow report RESULTS).
  if (const auto text = read_text_file(o.study_file)) store.record_study_file(study.name, o.study_file, *text);
  std::cerr << fmt::format("study '{}'{}: {} jobs on {} worker threads, store {}\n", study.name,
                           o.quick ? " (quick)" : "", jobs.size(), o.jobs, db.string());
  g_cancel.store(false);
  CancelOnSignal signals;
  RunnerOptions options;
  options.workers = o.jobs;
  options.cancel = &g_cancel;
  options.progress = &std::cerr;
  options.tty = isatty(STDERR_FILENO) != 0;
  RunnerSummary s = run_jobs(jobs, store, options);
  if (!s.cancelled && s.failed.empty() && study.confirm.enabled) s = run_confirm_stage(study, store, options, s);
  if (s.cancelled) {
    std::cerr << fmt::format("interrupted: {} runs stored in {} ({} of this study's {} jobs); run the same command "
                             "again to resume\n",
                             store.count(), db.string(), s.already_stored + s.done_now, s.total);
    return kInterrupted;
  }
  std::cerr << fmt::format("study '{}': {} runs done now, {} already stored, {} failed ({} jobs, store {})\n",
                           study.name, s.done_now, s.already_stored, s.failed.size(), s.total, db.string());
  for (const FailedJob& f : s.failed)
    std::cerr << fmt::format("  failed {} series '{}' point {} '{}' model {} replicate {}: {}\n", f.id.key,
                             f.id.series, f.id.point, f.id.point_label, f.id.model, f.id.replicate, f.error);
  return s.failed.empty() ? 0 : kExitFailure;
}

int cmd_export(const StudyCommands::Options& o) {
  const Store store(o.export_db, StoreAccess::read);
  if (o.csv == "-") {
    store.export_csv(o.table, std::cout);
    return 0;
  }
  write_file_atomically(o.csv, [&](std::ostream& out) { store.export_csv(o.table, out); });
  return 0;
}

}  // namespace

StudyCommands::StudyCommands(CLI::App& app) : o_(std::make_unique<Options>()) {
  Options& o = *o_;
  o.study = app.add_subcommand(
      "study", "Run a study (sweeps x models x replicates) into a SQLite store; resumes where it stopped");
  o.study->add_option("study", o.study_file, "Study file (TOML), e.g. studies/examples/tiny.toml")->required();
  o.study->add_flag("--quick", o.quick, "Use the study's [quick] settings (fewer replicates, models, values)");
  o.study->add_option("--jobs", o.jobs, "Worker threads (default: all cores; results do not depend on it)")
      ->check(CLI::Range(1, 1024));
  o.study->add_option("--db", o.db,
                      "Results store (default: results/<study name>/runs.sqlite; with --quick "
                      "results/<study name>-quick/runs.sqlite)");
  o.study->add_flag("--dry-run", o.dry_run, "Print the job count per series and model, and exit");

  o.export_cmd = app.add_subcommand("export", "Export one table of a study's results store as CSV");
  o.export_cmd->add_option("db", o.export_db, "Results store (runs.sqlite)")->required();
  o.export_cmd->add_option("--table", o.table, "Table to export")
      ->check(CLI::IsMember(Store::tables()));
  o.export_cmd->add_option("--csv", o.csv, "Output CSV file ('-': standard output)");
}

StudyCommands::~StudyCommands() = default;

std::optional<int> StudyCommands::run() const {
  const bool study = o_->study->parsed(), exporting = o_->export_cmd->parsed();
  if (!study && !exporting) return std::nullopt;
  return exit_code_of([&] { return study ? cmd_study(*o_) : cmd_export(*o_); });
}

}  // namespace gapflow

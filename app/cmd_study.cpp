#include "app/cmd_study.hpp"

#include "app/cancel_on_signal.hpp"
#include "app/cli_errors.hpp"
#include "common/text_file.hpp"

#include "studies/jobs.hpp"
#include "studies/confirm.hpp"
#include "studies/mpi_runner.hpp"
#include "studies/runner.hpp"
#include "studies/screen.hpp"
#include "studies/sequential.hpp"
#include "studies/shard.hpp"
#include "studies/store.hpp"
#include "studies/study.hpp"

#include <CLI/CLI.hpp>
#include <fmt/format.h>

#include <atomic>
#include <csignal>
#include <fstream>
#include <iostream>
#include <functional>
#include <map>
#include <memory>
#include <thread>
#include <unistd.h>

namespace gapflow {

struct StudyCommands::Options {
  CLI::App* study = nullptr;
  std::string study_file, db;
  bool quick = false, dry_run = false;
  bool plan = false, status = false, mpi = false;  // cluster: studies/shard.hpp, merge.hpp, mpi_runner.hpp
  std::string shard;                               // "I/K": run share I of K only
  int shards = 1;                                  // K for --plan without --shard
  int jobs = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));

  CLI::App* export_cmd = nullptr;
  std::string export_db, table = "runs", csv = "-";
};

namespace {

// --quick has its own store: its screen may confirm other points than the full
// study's, and those must not pass for the full study's confirmation.
// A share of a sharded study has its own store beside the study's: results/<name>/shards/shard-I-of-K.sqlite.
std::filesystem::path db_path(const StudyCommands::Options& o, const StudyDef& study,
                              const std::optional<ShardSpec>& shard) {
  if (!o.db.empty()) return o.db;
  const std::filesystem::path folder = std::filesystem::path("results") / (o.quick ? study.name + "-quick" : study.name);
  if (shard) return folder / "shards" / fmt::format("shard-{}-of-{}.sqlite", shard->index, shard->count);
  return folder / "runs.sqlite";
}

// --status: every job of the study (or of the share) by key, done or missing in the store.
int print_status(const std::vector<Job>& jobs, const std::filesystem::path& db) {
  std::set<std::string> stored;
  if (std::filesystem::exists(db)) stored = Store(db, StoreAccess::read).keys();
  int done = 0;
  for (const Job& j : jobs) {
    const bool is_done = stored.count(j.id.key) > 0;
    done += is_done ? 1 : 0;
    std::cout << fmt::format("{} {:7s} {} '{}' {} r{}\n", j.id.key, is_done ? "done" : "missing", j.id.series,
                             j.id.point_label, j.id.model, j.id.replicate);
  }
  std::cout << fmt::format("{} of {} jobs done, {} missing (store {})\n", done, jobs.size(), jobs.size() - done,
                           db.string());
  return 0;
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
  if (study.sequential.enabled)
    std::cout << fmt::format("sequential: up to {} replicates per point, in batches of {}, until J is within "
                             "+-{:.3g} % (jobs below: the minimum)\n",
                             study.sequential.max_replicates, study.sequential.batch,
                             100 * study.sequential.target_halfwidth);
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
                                RunnerSummary screen, const JobRunner& run) {
  const std::vector<RankedPoint> ranked = rank_screened_points(study, store.load(study.name));
  std::cerr << fmt::format("screen ranking by mean J_{} (best first; the top {} are confirmed with {}):\n",
                           study.confirm.rank_by, study.confirm.top, to_string(study.confirm.model));
  for (size_t i = 0; i < ranked.size() && i < static_cast<size_t>(study.confirm.top) + 5; ++i)
    std::cerr << fmt::format("  {:2d}. {:12s} {:40s} J = {:8.2f} /s ({} runs)\n", i + 1, ranked[i].series,
                             ranked[i].point_label, ranked[i].mean_j, ranked[i].runs);
  const RunnerSummary c = run(confirm_jobs(study, ranked), store, options);
  screen.total += c.total;
  screen.already_stored += c.already_stored;
  screen.done_now += c.done_now;
  screen.failed.insert(screen.failed.end(), c.failed.begin(), c.failed.end());
  screen.cancelled = c.cancelled;
  return screen;
}

// A [screen] study decides its jobs round by round (studies/screen.hpp): it has no fixed job
// list to shard, plan or list; --dry-run prints its grid and its largest possible cost.
int screen_dry_run_or_refuse(const StudyCommands::Options& o, const StudyDef& study) {
  if (!o.shard.empty() || o.plan || o.status)
    throw ScenarioError({o.study_file, 0, 0}, "", "",
                        "a [screen] study decides its jobs round by round: --shard, --plan and --status do not "
                        "apply (run it whole, or under --mpi)");
  if (!o.dry_run) return -1;
  const ScreenGrid g = screen_grid(study);
  const RacingParams& p = study.screen->racing;
  const std::size_t raced = g.raced.size(), gaps = g.baselines.size();
  std::cout << fmt::format("screen '{}': {} cells, {} feasible, {} gaps; {} rounds ({} to {} replicates), {} "
                           "confirmation replicates per survivor and {} per baseline\nat most {} runs (no cell "
                           "dropped); a fixed grid at the final confidence: {} runs\n",
                           study.name, g.cells.size(), raced, gaps, race_rounds(p), p.initial, p.max, p.confirm,
                           baseline_confirm_count(p), most_race_runs(p, raced, gaps), fixed_grid_runs(p, raced, gaps));
  if (const ScreenDef& s = *study.screen; s.check_model)
    std::cout << fmt::format("then a check in {}: {} fresh replicates per cell above J_0, per control ({}) and per "
                             "baseline of their gaps (the number of cells above J_0 is known only at the end)\n",
                             to_string(*s.check_model), s.check_replicates, s.check_controls);
  return 0;
}

int cmd_study(const StudyCommands::Options& o) {
  // MPI first: every rank reads the study (a bad one fails on all ranks alike); rank 0 runs it.
  std::unique_ptr<MpiSession> mpi = o.mpi ? std::make_unique<MpiSession>() : nullptr;
  StudyDef study = load_study(o.study_file);
  if (o.quick && !study.quick.present)  // silently running the full study would be no quick look
    throw ScenarioError({o.study_file, 0, 0}, "", "",
                        "this study has no [quick] table, so no quick variant: run it without --quick, "
                        "or add [quick] with replicates / models / thin");
  if (o.quick) study = apply_quick(std::move(study));
  if (study.screen)
    if (const int rc = screen_dry_run_or_refuse(o, study); rc >= 0) return rc;
  const std::optional<ShardSpec> shard = o.shard.empty() ? std::nullopt : std::optional(parse_shard(o.shard));
  const std::vector<Job> all_jobs = study.screen ? std::vector<Job>{} : expand_jobs(study);  // every scenario validated before anything runs
  const std::vector<Job> jobs = shard ? jobs_of_shard(all_jobs, *shard) : all_jobs;
  const std::filesystem::path db = db_path(o, study, shard);
  if (o.plan) {
    write_plan(std::cout, all_jobs, shard ? shard->count : o.shards, shard ? &*shard : nullptr);
    return 0;
  }
  if (o.status) return print_status(jobs, db);
  if (o.dry_run) {
    print_dry_run(study, jobs, db);
    return 0;
  }
  g_cancel.store(false);
  CancelOnSignal signals;
  if (mpi && mpi->rank() > 0) {
    mpi->worker_loop(&g_cancel);
    return 0;
  }
  Store store(db, StoreAccess::exclusive);  // a second study on this store refuses here
  // The report reads the study's [report] settings from the store (gapflow report RESULTS).
  if (const auto text = read_text_file(o.study_file)) store.record_study_file(study.name, o.study_file, *text);
  if (shard) {  // the whole job list, so that a merge of the shares can say which jobs are missing
    store.set_shard(shard->label());
    store.record_plan(plan_of(all_jobs, shard->count));
  }
  std::cerr << fmt::format("study '{}'{}{}: {} jobs on {}, store {}\n", study.name, o.quick ? " (quick)" : "",
                           shard ? fmt::format(" share {} ({} jobs in all)", shard->label(), all_jobs.size()) : "",
                           study.screen ? std::string("round-by-round") : std::to_string(jobs.size()),
                           mpi ? fmt::format("{} MPI ranks", mpi->size() - 1) : fmt::format("{} worker threads", o.jobs),
                           db.string());
  RunnerOptions options;
  options.workers = o.jobs;
  options.cancel = &g_cancel;
  options.progress = &std::cerr;
  options.tty = isatty(STDERR_FILENO) != 0;
  const JobRunner run = mpi ? JobRunner([&](const std::vector<Job>& j, Store& s, const RunnerOptions& op) {
    return mpi->run_jobs(j, s, op);
  })
                            : JobRunner(run_jobs);
  RunnerSummary s = study.screen ? run_screen(study, store, options, run, std::cerr) : run(jobs, store, options);
  if (study.sequential.enabled && shard && !s.cancelled)  // the rounds decide from every share's runs
    std::cerr << fmt::format("sequential rounds run once the shares are merged: gapflow study {} --db MERGED.sqlite\n",
                             o.study_file);
  else if (study.sequential.enabled && !s.cancelled && s.failed.empty())
    s = run_sequential_rounds(study, store, options, s, run, &std::cerr);
  const bool confirm = !s.cancelled && s.failed.empty() && study.confirm.enabled;
  if (confirm && shard)  // the ranking needs every share's screen: it runs after the merge
    std::cerr << fmt::format("[confirm] runs once the shares are merged: gapflow study {} --db MERGED.sqlite\n",
                             o.study_file);
  else if (confirm)
    s = run_confirm_stage(study, store, options, s, run);
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
  auto* dry = o.study->add_flag("--dry-run", o.dry_run, "Print the job count per series and model, and exit");
  // Clusters (README "Running a study on a cluster").
  auto* plan = o.study->add_flag(
      "--plan", o.plan, "Print the job list as JSON lines (key, share, expected cost, resolved scenario) and exit");
  o.study->add_option("--shard", o.shard,
                      "Run share I of K only (stable by job key, balanced by expected cost), into its own store "
                      "(default results/<name>/shards/shard-I-of-K.sqlite); e.g. --shard 3/8");
  o.study->add_option("--shards", o.shards, "With --plan and no --shard: the number of shares to list")
      ->check(CLI::Range(1, 100000));
  auto* status = o.study->add_flag("--status", o.status, "List every job (of the share) as done or missing, and exit");
  auto* mpi = o.study->add_flag("--mpi", o.mpi,
                                "Run as an MPI job (mpirun -np N gapflow study ... --mpi): rank 0 hands out jobs "
                                "and writes the store, the others simulate");
  plan->excludes(dry)->excludes(status)->excludes(mpi);
  status->excludes(dry)->excludes(mpi);

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

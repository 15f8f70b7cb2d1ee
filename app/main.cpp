// gapflow: the command line.
//   gapflow run SCENARIO.toml [--model 2d|3d] [--set key=value]... [--out record.json]
//       [--snapshot-at 0,5 --snapshot-dir DIR] [--snapshot-on-clog] [--movie out.mp4] [--vtk DIR]
//   gapflow check SCENARIO.toml [--set key=value]... [--print]
//   gapflow study STUDY.toml [--quick] [--jobs N] [--db PATH] [--dry-run]
//   gapflow export DB --table TABLE --csv OUT.csv
//   gapflow report RESULTS [--study STUDY.toml] [--out DIR] [--no-plots] [--no-snapshots]
//   gapflow calibrate DATA.toml [--model 2d|3d] ...   gapflow twin DATA.toml --out ... --truth ...
//   gapflow merge OUT.sqlite SHARD.sqlite... | compare A.sqlite B.sqlite | slurm STUDY.toml [--array-size K]
//   gapflow serve SCENARIO.toml [--model 2d|3d] [--port 8080]   (live view in a browser)
// Exit codes: 0 success, 2 bad input (scenario, study, store, paths, command line), 1 failure while
// running (including lost standard output and runs whose particles escaped), 130 interrupted study.
#include "app/cli_errors.hpp"
#include "app/cmd_calibrate.hpp"
#include "app/cmd_cluster.hpp"
#include "app/cmd_report.hpp"
#include "app/cmd_serve.hpp"
#include "app/cmd_study.hpp"
#include "app/run_output_options.hpp"
#include "models/registry.hpp"
#include "common/geometry.hpp"
#include "common/scenario_loader.hpp"
#include "common/statistics.hpp"
#include "common/steady_state.hpp"
#include "common/text_file.hpp"
#include "common/units.hpp"

#include <CLI/CLI.hpp>
#include <atomic>
#include <cstdio>
#include <mutex>
#include <filesystem>
#include <fmt/format.h>
#include <fstream>
#include <iostream>
#include <thread>

namespace {

using namespace gapflow;


struct ScenarioArgs {
  std::string file;
  std::vector<std::string> overrides;
};

void add_scenario_args(CLI::App* cmd, ScenarioArgs& a) {
  cmd->add_option("scenario", a.file, "Scenario file (TOML), e.g. scenarios/paper/no_obstruction_medium.toml")
      ->required();
  cmd->add_option("--set", a.overrides,
                  "Override one scenario key, validated like the file, e.g. --set obstruction.distance_mm=20 "
                  "(repeatable)")
      ->take_all()
      ->allow_extra_args(false);
}

// Load, validate and compile; errors carry file:line:column and the key.
// With a model: also what that model cannot run (check_model_supports), located like the rest.
CompiledScenario load_and_compile(const ScenarioArgs& a, std::optional<ModelKind> model = std::nullopt) {
  LoadedScenario loaded = load_scenario(a.file, a.overrides);
  try {
    CompiledScenario sc = compile_scenario(loaded.def);
    if (model) check_model_supports(sc, *model);
    return sc;
  } catch (const ScenarioInvalid& e) {
    throw locate(e, loaded);
  }
}

// Replicates r0 .. r0+n-1 of one scenario, on `jobs` worker threads. Each run is
// single-threaded and seeded by its replicate, so the records do not depend on jobs.
std::vector<RunRecord> run_replicates(const ScenarioArgs& a, ModelKind kind, int n, int jobs) {
  std::vector<CompiledScenario> scenarios;
  const int r0 = load_and_compile(a).def.run.replicate;
  for (int i = 0; i < n; ++i) {
    ScenarioArgs ai = a;
    ai.overrides.push_back("run.replicate=" + std::to_string(r0 + i));
    scenarios.push_back(load_and_compile(ai));
  }
  std::vector<RunRecord> records(static_cast<size_t>(n));
  std::atomic<int> next{0};
  std::exception_ptr failure;
  std::mutex failure_mutex;
  auto worker = [&] {
    for (int i; (i = next++) < n;) {
      try {
        records[static_cast<size_t>(i)] = run_model(scenarios[static_cast<size_t>(i)], kind);
      } catch (...) {
        std::lock_guard lock(failure_mutex);
        failure = std::current_exception();
      }
    }
  };
  std::vector<std::thread> pool;
  for (int j = 0; j < std::max(1, std::min(jobs, n)); ++j) pool.emplace_back(worker);
  for (auto& t : pool) t.join();
  if (failure) std::rethrow_exception(failure);
  return records;
}

void print_replicate_table(const std::vector<RunRecord>& records) {
  auto opt = [](const std::optional<double>& v) { return v ? fmt::format("{:9.2f}", *v) : std::string("      n/a"); };
  std::cout << "replicate  passed  escaped  J_paper/s  J_flow/s   J_mid/s  clogs  regime        sim_s  wall_s\n";
  std::vector<double> jp, jf, jm, js;
  for (const RunRecord& r : records) {
    std::cout << fmt::format("{:9d}  {:6d}  {:7d}  {}  {} {}  {:5d}  {:12s} {:6.1f}  {:6.1f}\n", r.replicate, r.passed,
                             r.escaped, opt(r.j_paper), opt(r.j_flowing), opt(r.j_mid), r.clogs.size(),
                             to_string(r.regime), r.sim_time_s, r.wall_time_s);
    if (r.j_paper) jp.push_back(*r.j_paper);
    if (r.j_flowing) jf.push_back(*r.j_flowing);
    if (r.j_mid) jm.push_back(*r.j_mid);
    if (const auto e = steady_state_of(r); e && e->valid) js.push_back(e->j_per_s);  // re-injected runs only
  }
  const double d = records.front().diameter_m;
  auto line = [&](const char* name, const std::vector<double>& v) {
    const Summary s = summarize(v);
    std::cout << fmt::format("{:10s} n = {:3d}  mean {:8.3f} /s  95% CI +-{:.3f} ({:.2f} %)  J*sqrt(d/g) = {:.4f}\n",
                             name, s.n, s.mean, s.ci95_half, s.n ? 100 * s.ci95_half / s.mean : 0.0,
                             dimensionless_flow_rate(s.mean, d));
  };
  line("J_paper", jp);
  line("J_flowing", jf);
  line("J_mid", jm);
  if (!js.empty()) line("J_steady", js);  // interval over runs; each run's batch-means interval: --out or one run
}

int cmd_run(const ScenarioArgs& a, const std::string& model_name, const std::string& out_path, bool quiet,
            int replicates, int jobs, const RunOutputOptions& output_options) {
  const ModelKind kind = parse_model_kind(model_name);
  const CompiledScenario sc = load_and_compile(a, kind);
  const RunOutputDef output_def = output_options.resolved();
  if (replicates > 1) {
    if (!out_path.empty()) throw std::invalid_argument("--out writes one run record: use it without --replicates");
    if (output_def.any())
      throw std::invalid_argument("snapshots, --movie and --vtk show one run: use them without --replicates");
    if (!quiet)
      std::cerr << fmt::format("running {} replicates of '{}' in {} on {} worker threads...\n", replicates,
                               sc.def.name, to_string(kind), jobs);
    const std::vector<RunRecord> records = run_replicates(a, kind, replicates, jobs);
    print_replicate_table(records);
    int invalid = 0;
    for (const RunRecord& r : records) invalid += invalid_run_reason(r) ? 1 : 0;
    if (invalid == 0) return 0;
    std::cerr << fmt::format("error: {} of {} replicates are not valid discharges (particles escaped)\n", invalid,
                             records.size());
    return kExitFailure;
  }
  if (!out_path.empty()) check_output_file(out_path);  // before the simulation, not after it
  if (!quiet)
    std::cerr << fmt::format("running '{}' in {} with {} particles...\n", sc.def.name, to_string(kind),
                             sc.particles.size());
  std::unique_ptr<RunOutputs> outputs;
  if (output_def.any()) outputs = std::make_unique<RunOutputs>(sc, output_def);
  const RunRecord record = run_model(sc, kind, outputs ? &outputs->observer() : nullptr);
  if (outputs)
    for (const std::string& line : outputs->finish()) std::cerr << line << "\n";
  write_summary(std::cout, record);
  if (!out_path.empty()) write_file_atomically(out_path, [&](std::ostream& o) { write_json(o, record); });
  if (auto why = invalid_run_reason(record)) {
    std::cerr << "error: " << *why << "\n";
    return kExitFailure;
  }
  return 0;
}

// Without --model: valid for at least one model, and which ones refuse it is said (a
// vertical silo with rolling spheres is refused by the 2D model, a 70 deg board by the 3D one).
int cmd_check(const ScenarioArgs& a, bool print, const std::string& model_name) {
  if (!model_name.empty()) (void)load_and_compile(a, parse_model_kind(model_name));
  const CompiledScenario sc = load_and_compile(a);
  if (model_name.empty()) {
    std::vector<std::string> refused;
    for (ModelKind k : {ModelKind::box2d, ModelKind::bullet}) {
      try {
        check_model_supports(sc, k);
      } catch (const ScenarioInvalid& e) {
        refused.push_back(fmt::format("the {} model refuses it: {}", to_string(k), e.what()));
      }
    }
    if (refused.size() == 2) (void)load_and_compile(a, ModelKind::box2d);  // neither runs it: the 2D error, located
    for (const std::string& r : refused) std::cerr << "note: " << r << "\n";
  }
  if (print) std::cout << canonical_toml(sc.def);
  std::cerr << fmt::format("{}: ok ('{}', {} particles, W/d = {:.3f}, hash {:016x})\n", a.file, sc.def.name,
                           sc.particles.size(), sc.w_over_d(), sc.scenario_hash);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "gapflow: granular flow through a bottleneck with obstructions.\n"
      "Spheres roll down an inclined board into a bottleneck and out through a gap W; an obstruction at\n"
      "distance D from the gap can raise the flow rate J. One scenario file drives a fast 2D model (Box2D)\n"
      "and a full 3D model (Bullet). Start with:\n"
      "  gapflow run scenarios/paper/no_obstruction_medium.toml\n"
      "  gapflow check scenarios/paper/cylinder.toml --set obstruction.distance_mm=90\n"};
  app.require_subcommand(1);

  ScenarioArgs run_args;
  std::string model = "2d", out_path;
  bool quiet = false;
  CLI::App* run = app.add_subcommand("run", "Run one simulation and print J, clogs and timing");
  add_scenario_args(run, run_args);
  run->add_option("--model", model, "Model: 2d (Box2D, reduced) or 3d (Bullet, full)")
      ->check(CLI::IsMember({"2d", "3d"}));
  run->add_option("--out", out_path, "Write the complete run record (crossings, avalanches, clogs) as JSON");
  run->add_flag("--quiet", quiet, "Do not print progress to stderr");
  int replicates = 1, jobs = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  run->add_option("--replicates", replicates,
                  "Run this many replicates (run.replicate, +1, ...) and print mean J with 95 % intervals")
      ->check(CLI::Range(1, 100000));
  run->add_option("--jobs", jobs, "Worker threads for --replicates (results do not depend on it)")
      ->check(CLI::Range(1, 1024));
  RunOutputOptions run_outputs;
  add_run_output_options(run, run_outputs);

  ScenarioArgs check_args;
  bool print = false;
  CLI::App* check = app.add_subcommand("check", "Validate a scenario (and its --set overrides) without running");
  add_scenario_args(check, check_args);
  check->add_flag("--print", print, "Print the complete resolved scenario as canonical TOML");
  std::string check_model;
  check->add_option("--model", check_model, "Also check that this model (2d | 3d) can run it; without it, say which refuses it")
      ->check(CLI::IsMember({"2d", "3d"}));

  gapflow::StudyCommands study_commands(app);
  gapflow::ReportCommand report_command(app);
  gapflow::CalibrateCommands calibrate_commands(app);
  gapflow::ClusterCommands cluster_commands(app);
  gapflow::ServeCommand serve_command(app);

  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    app.exit(e);
    return kExitBadInput;
  }

  int code = 0;
  if (auto c = study_commands.run()) code = *c;
  else if (auto c = report_command.run()) code = *c;
  else if (auto c = calibrate_commands.run()) code = *c;
  else if (auto c = cluster_commands.run()) code = *c;
  else if (auto c = serve_command.run()) code = *c;
  else code = exit_code_of([&] {
    if (*run) return cmd_run(run_args, model, out_path, quiet, replicates, jobs, run_outputs);
    if (*check) return cmd_check(check_args, print, check_model);
    return 0;
  });
  // Output lost on the way (`> /dev/full`, a closed pipe) must not pass for success.
  if (auto why = flush_stdout()) {
    std::cerr << "error: cannot write to standard output: " << *why << "\n";
    if (code == 0) code = kExitFailure;
  }
  return code;
}

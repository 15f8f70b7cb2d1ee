#include "app/cmd_calibrate.hpp"

#include "app/cancel_on_signal.hpp"
#include "app/cli_errors.hpp"
#include "calibrate/calibration_report.hpp"
#include "calibrate/twin.hpp"
#include "common/text_file.hpp"
#include "studies/mpi_runner.hpp"

#include <CLI/CLI.hpp>
#include <fmt/format.h>

#include <iostream>
#include <thread>
#include <unistd.h>

namespace gapflow {

struct CalibrateCommands::Options {
  CLI::App* calibrate = nullptr;
  CLI::App* twin = nullptr;
  std::string data_file, model = "2d", out, db, truth;
  int jobs = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  bool no_plots = false, mpi = false, check = false;
  int max_effects = 2;
  int contenders = CalibrationDef{}.contenders;
  int alternatives = CalibrationDef{}.alternatives;
  int model_replicates = 0;  // 0: the data file's [model] replicates
  double decisive_score_p = CalibrationDef{}.decisive_score_p;
  bool held_out_route = CalibrationDef{}.held_out_route;
  bool independent_signatures = CalibrationDef{}.independent_signatures;
  // twin
  std::uint64_t seed = 1;
  std::vector<std::string> effects, set;
  int replicates = 10;
  std::uint64_t model_seed = 0;
  CLI::Option* model_seed_given = nullptr;  // --model-seed (else the design's [model] seed)
  std::string name;
};

namespace {

EvaluatorOptions evaluator_options(const CalibrateCommands::Options& o) {
  EvaluatorOptions e;
  e.model = parse_model_kind(o.model);
  e.workers = o.jobs;
  e.cancel = &g_cancel;
  e.progress = &std::cerr;
  e.tty = isatty(STDERR_FILENO) != 0;
  return e;
}

// --check: the data file read, every point's scenario resolved and compiled, nothing run.
int print_data_check(const DataFile& data) {
  std::cout << fmt::format("{}: {} points ({} held out), observable {}, {} free parameter(s), {} model "
                           "replicates per point; source: {} ({})\n",
                           data.name, data.points.size(), data.points.size() - data.fitted_count(),
                           data.observables_text(), data.free.size(),
                           data.model_replicates, data.source.citation, data.source.method);
  return 0;
}

// --model-replicates: the model's runs per point and parameter value, in place of the data file's
// [model] replicates. The data's own noise is the data's; the model's shrinks with its replicates, and
// every test of the loop compares the residual against the two together: more model replicates, more
// power, at a cost in runs (replicates 1..n of a parameter set are the same runs whatever n is, so
// raising n reuses the store's runs and simulates only the new replicates).
DataFile with_model_replicates(DataFile data, int model_replicates) {
  if (model_replicates > 0) data.model_replicates = model_replicates;
  return data;
}

int cmd_calibrate(const CalibrateCommands::Options& o) {
  const DataFile data = with_model_replicates(load_data_file(o.data_file), o.model_replicates);
  check_points_run_in(data, parse_model_kind(o.model));  // exit 2 now, not at the first run
  if (o.check) return print_data_check(data);
  const std::filesystem::path out = o.out.empty() ? std::filesystem::path("results/calibration") / data.name : std::filesystem::path(o.out);
  check_output_folder(out);  // before an hour of runs, not after
  const std::filesystem::path db = o.db.empty() ? out / "runs.sqlite" : std::filesystem::path(o.db);
  CalibrationDef def;
  def.model = parse_model_kind(o.model);
  def.max_effects = o.max_effects;
  def.contenders = o.contenders;
  def.alternatives = o.alternatives;
  def.decisive_score_p = o.decisive_score_p;
  def.held_out_route = o.held_out_route;
  def.independent_signatures = o.independent_signatures;
  // Under MPI every rank has read and checked the data file; ranks >= 1 only simulate.
  std::unique_ptr<MpiSession> mpi = o.mpi ? std::make_unique<MpiSession>() : nullptr;
  g_cancel.store(false);
  CancelOnSignal signals;
  if (mpi && mpi->rank() > 0) {
    mpi->worker_loop(&g_cancel);
    return 0;
  }
  Store store(db, StoreAccess::exclusive);  // one calibration or twin per store at a time
  EvaluatorOptions options = evaluator_options(o);
  if (mpi)
    options.runner = [&](const std::vector<Job>& jobs, Store& s, const RunnerOptions& ro) { return mpi->run_jobs(jobs, s, ro); };
  Evaluator ev(data, store, options);
  std::cerr << fmt::format("calibrate '{}' against the {} model: {} points ({} held out), {} replicates per point, store {}\n",
                           data.name, o.model, data.points.size(), data.points.size() - data.fitted_count(),
                           data.model_replicates, db.string());
  try {
    const CalibrationResult r = calibrate(data, def, ev);
    write_calibration_outputs(data, r, out, !o.no_plots);
    std::cout << fmt::format("{}: {}", data.name, r.verdict);
    for (const AddedEffect& e : r.effects) std::cout << fmt::format("; {} = {:.4g} [{:.4g}, {:.4g}]", e.key, e.value, e.lo95, e.hi95);
    std::cout << fmt::format("\nheld-out RMS/noise {:.2f} -> {:.2f}, fitted chi2/nu {:.2f} -> {:.2f}; report {}\n",
                             r.before.held_out.rms_whitened, r.after.held_out.rms_whitened, r.before.fitted.chi.per_dof(),
                             r.after.fitted.chi.per_dof(), (out / "report.md").string());
    return 0;
  } catch (const RunCancelled&) {
    std::cerr << fmt::format("interrupted: {} runs stored in {}; run the same command again to resume\n", store.count(),
                             db.string());
    return kInterrupted;
  }
}

int cmd_twin(const CalibrateCommands::Options& o) {
  const DataFile design = load_data_file(o.data_file);
  if (std::filesystem::exists(o.out) || std::filesystem::exists(o.truth))
    throw std::invalid_argument(fmt::format("twin: {} or {} exists already; twins never overwrite files", o.out, o.truth));
  TwinDef def;
  def.name = o.name.empty() ? std::filesystem::path(o.out).stem().string() : o.name;
  def.model = parse_model_kind(o.model);
  check_points_run_in(design, def.model);
  def.seed = o.seed;
  def.effects = o.effects;
  def.set = o.set;
  def.replicates = o.replicates;
  if (o.model_seed_given->count() > 0) def.model_seed = o.model_seed;
  (void)draw_twin(design, def);  // bad effect names and sizes are input errors, before anything runs
  const std::filesystem::path db = o.db.empty() ? std::filesystem::path(o.out).parent_path() / "twin_runs.sqlite"
                                                : std::filesystem::path(o.db);
  Store store(db, StoreAccess::exclusive);  // one calibration or twin per store at a time
  g_cancel.store(false);
  CancelOnSignal signals;
  Evaluator ev(design, store, evaluator_options(o));
  try {
    make_twin(design, def, ev, o.out, o.truth);
  } catch (const RunCancelled&) {
    std::cerr << "interrupted; run the same command again to resume\n";
    return kInterrupted;
  }
  std::cout << fmt::format("twin '{}' written to {} (truth in {})\n", def.name, o.out, o.truth);
  return 0;
}

}  // namespace

CalibrateCommands::CalibrateCommands(CLI::App& app) : o_(std::make_unique<Options>()) {
  Options& o = *o_;
  o.calibrate = app.add_subcommand(
      "calibrate", "Fit a model to a measured-data file, trace the residual to a missing effect, report before/after");
  o.calibrate->add_option("data", o.data_file, "Measured-data file (TOML), e.g. data/silo/janda2008.toml")->required();
  o.calibrate->add_option("--model", o.model, "Model: 2d or 3d")->check(CLI::IsMember({"2d", "3d"}));
  o.calibrate->add_option("--jobs", o.jobs, "Worker threads (results do not depend on it)")->check(CLI::Range(1, 1024));
  o.calibrate->add_option("--out", o.out, "Output folder (default results/calibration/<data name>/)");
  o.calibrate->add_option("--db", o.db, "Runs store (default <out>/runs.sqlite; calibrations may share one)");
  o.calibrate->add_option("--max-effects", o.max_effects, "Rounds of adding an effect")->check(CLI::Range(0, 4));
  o.calibrate->add_option("--contenders", o.contenders,
                          "Significant candidates fitted in full before one is tried, the lowest BIC (default 1: the "
                          "best score is tried; blind passes 11-12 identified as many with 1 as with 3)")
      ->check(CLI::Range(1, 10));
  o.calibrate->add_option("--alternatives", o.alternatives,
                          "Other significant candidates fitted in full beside the one tried: any that alone leaves the "
                          "fitted points within the noise is an alternative these data do not exclude, and the verdict "
                          "says so (default 2; 0: none asked; rule 5 of calibrate/decisions.hpp)")
      ->check(CLI::Range(0, 9));
  o.calibrate->add_option("--decisive-score", o.decisive_score_p,
                          "Adjusted p below which the best candidate is tried even where the fitted chi2 is within "
                          "the noise (default 0: never; rule 1 of calibrate/decisions.hpp)")
      ->check(CLI::Range(0.0, 0.05));
  o.calibrate->add_flag("--held-out-route", o.held_out_route,
                        "Also look for an effect where the fitted points are within the noise but the held-out points "
                        "are not (default off; rule 1 of calibrate/decisions.hpp)");
  o.calibrate->add_flag("--independent-signatures,!--shared-signatures", o.independent_signatures,
                        "Measure the effects' signatures on seeds of their own (the default), or pair their moved runs "
                        "with the baseline nodes' runs, which the residual shares, so every score leans toward its step "
                        "(--shared-signatures: every blind pass up to 18; calibrate/effect_responses.hpp)");
  o.calibrate->add_option("--model-replicates", o.model_replicates,
                          "Model runs per point and parameter value, in place of the data file's [model] replicates "
                          "(more: less model noise in every test, more runs)")
      ->check(CLI::Range(2, 1000));
  o.calibrate->add_flag("--no-plots", o.no_plots, "Do not draw the PNG figures");
  o.calibrate->add_flag("--check", o.check, "Read and check the data file (every point's scenario compiled), run nothing");
  o.calibrate->add_flag("--mpi", o.mpi,
                        "Run as an MPI job (mpirun -np N gapflow calibrate ... --mpi): rank 0 runs the loop and writes "
                        "the store, ranks 1..N-1 simulate; the result equals a local calibration");

  o.twin = app.add_subcommand("twin", "Write a data file made by a model with hidden effects (truth in a separate file)");
  o.twin->add_option("data", o.data_file, "Data file whose design (points, observable, free parameters) the twin copies")->required();
  o.twin->add_option("--out", o.out, "The twin data file to write (must not exist)")->required();
  o.twin->add_option("--truth", o.truth, "Where the planted values go (JSON; must not exist)")->required();
  o.twin->add_option("--model", o.model, "Model that makes the data: 2d or 3d")->check(CLI::IsMember({"2d", "3d"}));
  o.twin->add_option("--seed", o.seed, "Draws the hidden sizes and the free parameters' true values");
  o.twin->add_option("--effect", o.effects, "Catalogue effect to plant: NAME, NAME:low, NAME:high or NAME=VALUE (repeatable)");
  o.twin->add_option("--set", o.set, "Plant key=value as it is (e.g. an effect outside the catalogue; repeatable)");
  o.twin->add_option("--replicates", o.replicates, "Runs per point behind each value")->check(CLI::Range(2, 1000));
  o.model_seed_given = o.twin->add_option("--model-seed", o.model_seed,
                                          "The [model] seed written into the twin for its calibrations (default: the "
                                          "design's; a blind study with one per twin samples the model's noise)");
  o.twin->add_option("--name", o.name, "[data] name of the twin (default: the file's stem)");
  o.twin->add_option("--jobs", o.jobs, "Worker threads")->check(CLI::Range(1, 1024));
  o.twin->add_option("--db", o.db, "Runs store (default: twin_runs.sqlite beside --out)");
}

CalibrateCommands::~CalibrateCommands() = default;

std::optional<int> CalibrateCommands::run() const {
  if (o_->calibrate->parsed()) return exit_code_of([&] { return cmd_calibrate(*o_); });
  if (o_->twin->parsed()) return exit_code_of([&] { return cmd_twin(*o_); });
  return std::nullopt;
}

}  // namespace gapflow

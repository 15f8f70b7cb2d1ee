// Study throughput: bench/study_throughput.toml (16 short 2D runs) expanded
// and run by the study runner (studies/runner.hpp) into a fresh SQLite store,
// with 1 and with 2 workers. Reports runs per minute of wall time and, for 2
// workers, the parallel efficiency rate(2) / (2 rate(1)) against the 1-worker
// repetitions run earlier in the same process.
#include "bench/bench_support.hpp"
#include "studies/runner.hpp"

#include <benchmark/benchmark.h>

#include <atomic>
#include <chrono>
#include <unistd.h>

namespace gapflow::bench {
namespace {

constexpr const char* kStudy = "bench/study_throughput.toml";

// Mean 1-worker rate of this process (repetitions of Study/workers:1 run first).
double g_rate1_sum = 0;
int g_rate1_count = 0;

// A store in a fresh temporary folder, removed afterwards (with its WAL files).
class TempStore {
 public:
  TempStore() {
    static std::atomic<int> serial{0};
    dir_ = std::filesystem::temp_directory_path() /
           ("gapflow_bench_" + std::to_string(getpid()) + "_" + std::to_string(serial++));
    std::filesystem::remove_all(dir_);
    store_ = std::make_unique<Store>(dir_ / "study.sqlite");
  }
  ~TempStore() {
    store_.reset();
    std::error_code ignored;
    std::filesystem::remove_all(dir_, ignored);
  }
  Store& store() { return *store_; }

 private:
  std::filesystem::path dir_;
  std::unique_ptr<Store> store_;
};

void BM_Study(benchmark::State& state) {
  const int workers = static_cast<int>(state.range(0));
  const std::vector<Job> jobs = expand_jobs(load_study(source_path(kStudy)));
  double crossings = 0, check = 0, wall = 0;
  int failed = 0;
  for (auto _ : state) {
    state.PauseTiming();  // a new store is part of the set-up, not of the throughput
    auto temp = std::make_unique<TempStore>();
    state.ResumeTiming();
    RunnerOptions options;
    options.workers = workers;
    const auto t0 = std::chrono::steady_clock::now();
    const RunnerSummary summary = run_jobs(jobs, temp->store(), options);
    wall += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    state.PauseTiming();
    failed += static_cast<int>(summary.failed.size());
    // Physics check: every crossing of every stored run, and their fingerprint.
    StateHash h;
    crossings = 0;
    for (const StoredRun& run : temp->store().load()) {
      crossings += static_cast<double>(run.record.passed);
      h.add(crossings_hash(run.record));
    }
    check = h.value();
    temp.reset();
    state.ResumeTiming();
  }
  if (failed > 0) state.SkipWithError("some study runs failed");
  const auto runs = static_cast<double>(jobs.size() * static_cast<std::size_t>(state.iterations()));
  // Wall clock (as ->UseRealTime()): runs side by side on several cores.
  state.counters["runs_per_min"] = 60.0 * runs / wall;
  state.counters["runs"] = static_cast<double>(jobs.size());
  state.counters["check_crossings"] = crossings;
  state.counters["check_hash"] = check;
  // Efficiency needs the 1-worker rate of the same process (the benchmark's
  // own timer is not readable here, hence the steady_clock around run_jobs).
  const double rate = 60.0 * runs / wall;  // runs per minute
  if (workers == 1) {
    g_rate1_sum += rate;
    ++g_rate1_count;
  } else if (g_rate1_count > 0) {
    state.counters["parallel_efficiency"] = rate / (workers * g_rate1_sum / g_rate1_count);
  }
}

BENCHMARK(BM_Study)
    ->Name("Study")
    ->ArgName("workers")
    ->Arg(1)->Arg(2)
    ->Iterations(1)
    ->UseRealTime()
    ->Unit(benchmark::kSecond);

}  // namespace
}  // namespace gapflow::bench

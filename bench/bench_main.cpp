// gapflow_bench: the benchmark suite's main. Like BENCHMARK_MAIN(), plus
//  * context in the JSON: load average at the start (the machine may be shared:
//    numbers taken under load are slower), code version, source tree;
//  * a default filter that leaves out the opt-in benchmarks (names containing
//    "Large"), used only when no --benchmark_filter is given;
//  * --set key=value (repeatable): an override applied to every scene except
//    the study's, for A/B experiments (recorded as context "gapflow_set").
#include "bench/bench_support.hpp"
#include "studies/store.hpp"

#include <benchmark/benchmark.h>

#include <sched.h>

#include <fstream>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

namespace {

std::string first_line(const char* file) {
  std::ifstream in(file);
  std::string line;
  std::getline(in, line);
  return line;
}

// "model name" of the first CPU in /proc/cpuinfo ("" when unknown).
std::string cpu_model() {
  std::ifstream in("/proc/cpuinfo");
  for (std::string line; std::getline(in, line);)
    if (line.rfind("model name", 0) == 0) {
      const auto colon = line.find(':');
      return colon == std::string::npos ? line : line.substr(line.find_first_not_of(" \t", colon + 1));
    }
  return "";
}

// CPUs this process may run on (what `nproc` prints; taskset narrows it).
int usable_cpus() {
  cpu_set_t set;
  CPU_ZERO(&set);
  if (sched_getaffinity(0, sizeof set, &set) != 0) return static_cast<int>(std::thread::hardware_concurrency());
  return CPU_COUNT(&set);
}

}  // namespace

int main(int argc, char** argv) {
  std::vector<char*> args{argv[0]};
  bool has_filter = false;
  std::string extras;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--set" && i + 1 < argc) {  // ours, not Google Benchmark's: an override for every scene
      gapflow::bench::extra_overrides().push_back(argv[++i]);
      extras += (extras.empty() ? "" : " ") + gapflow::bench::extra_overrides().back();
      continue;
    }
    if (a.rfind("--benchmark_filter", 0) == 0) has_filter = true;
    args.push_back(argv[i]);
  }
  // Google Benchmark 1.7 accepts a negative filter ("-regex": everything else).
  std::string default_filter = "--benchmark_filter=-Large";
  if (!has_filter) args.push_back(default_filter.data());
  int n = static_cast<int>(args.size());

  benchmark::Initialize(&n, args.data());
  if (benchmark::ReportUnrecognizedArguments(n, args.data())) return 1;
  benchmark::AddCustomContext("loadavg_at_start", first_line("/proc/loadavg"));
  benchmark::AddCustomContext("nproc", std::to_string(usable_cpus()));
  benchmark::AddCustomContext("cpu_model", cpu_model());
  benchmark::AddCustomContext("gapflow_code_version", gapflow::code_version());
  benchmark::AddCustomContext("gapflow_source_dir", GAPFLOW_SOURCE_DIR);
#ifdef NDEBUG
  benchmark::AddCustomContext("gapflow_build", "release");
#else
  benchmark::AddCustomContext("gapflow_build", "debug: timings not representative");
#endif
  // Set only for experiments: such a run is not comparable with the baseline.
  if (!extras.empty()) benchmark::AddCustomContext("gapflow_set", extras);
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}

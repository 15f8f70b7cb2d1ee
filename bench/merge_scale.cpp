// gapflow_merge_scale: how `gapflow merge` scales, on synthetic stores (README "Running a study
// on a cluster"; scripts/cluster_scale.sh runs it and writes results/cluster_scale/).
//
//   gapflow_merge_scale --runs 10000 --shards 64 --crossings 1140 --dir /tmp/x
//
// Writes `shards` stores holding `runs` runs in all, each with `crossings` crossings (the mean
// of the committed paper stores), one avalanche per 50 crossings and two clogs, then times
// the merge into a fresh store and a second merge of the same shards (idempotent: adds nothing).
// Prints key=value lines. Wall times on a shared machine: one measurement, not a baseline.
#include "studies/merge.hpp"
#include "studies/store.hpp"

#include <fmt/format.h>

#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <random>
#include <string>

using namespace gapflow;
namespace fs = std::filesystem;

namespace {

double seconds_since(std::chrono::steady_clock::time_point t) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
}

StoredRun synthetic_run(std::uint64_t key, int crossings, std::mt19937_64& rng) {
  std::uniform_real_distribution<double> u(0.0, 1.0);
  StoredRun run;
  run.id.key = fmt::format("{:016x}", key);
  run.id.study = "synthetic", run.id.series = "s", run.id.point = static_cast<int>(key % 100);
  run.id.point_label = fmt::format("obstruction.distance_mm={}", key % 100);
  run.id.axes_json = fmt::format("{{\"obstruction.distance_mm\":{}}}", key % 100);
  run.id.model = "2d", run.id.replicate = static_cast<int>(key / 100), run.id.run_seed = rng();
  run.id.scenario_hash = key;
  run.code_version = code_version();
  RunRecord& r = run.record;
  r.model = "2d", r.scenario_name = "synthetic", r.particles = crossings, r.passed = crossings;
  r.sim_time_s = 20 * u(rng), r.wall_time_s = 25 * u(rng), r.j_paper = 90 * u(rng), r.diameter_m = 0.00775;
  r.gap_m = 0.033, r.time_step_s = 0.001;
  for (int i = 0; i < crossings; ++i) r.crossings.push_back({i, 20 * u(rng), 0.03 * u(rng) - 0.015});
  for (int i = 0; i < crossings / 50; ++i) r.avalanches.push_back({50, u(rng), u(rng), i == 0, false});
  r.clogs = {{1.0, 0.5, false, 0.01, false}, {2.0, 0.5, true, 0.02, true}};
  return run;
}

}  // namespace

int main(int argc, char** argv) {
  int runs = 10000, shards = 64, crossings = 1140;
  fs::path dir;
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string a = argv[i], v = argv[i + 1];
    if (a == "--runs") runs = std::atoi(v.c_str());
    else if (a == "--shards") shards = std::atoi(v.c_str());
    else if (a == "--crossings") crossings = std::atoi(v.c_str());
    else if (a == "--dir") dir = v;
    else {
      std::cerr << "usage: gapflow_merge_scale --dir DIR [--runs N] [--shards K] [--crossings C]\n";
      return 2;
    }
  }
  if (dir.empty() || runs < 1 || shards < 1 || crossings < 0) {
    std::cerr << "usage: gapflow_merge_scale --dir DIR [--runs N] [--shards K] [--crossings C]\n";
    return 2;
  }
  fs::remove_all(dir);
  fs::create_directories(dir);
  std::mt19937_64 rng(1);
  std::vector<fs::path> paths;
  auto t = std::chrono::steady_clock::now();
  for (int k = 0; k < shards; ++k) {
    paths.push_back(dir / fmt::format("shard-{}-of-{}.sqlite", k + 1, shards));
    Store store(paths.back());
    std::vector<StoredRun> batch;
    std::vector<Provenance> provenance;
    for (int i = k; i < runs; i += shards) {
      batch.push_back(synthetic_run(static_cast<std::uint64_t>(i) * 0x9e3779b97f4a7c15ULL, crossings, rng));
      provenance.push_back({fmt::format("{}/{}", k + 1, shards), "synthetic", code_version(), ""});
    }
    store.import_runs(batch, provenance);
  }
  const double make_s = seconds_since(t);
  std::uintmax_t shard_bytes = 0;
  for (const auto& p : paths) shard_bytes += fs::file_size(p);

  t = std::chrono::steady_clock::now();
  Store out(dir / "merged.sqlite");
  const MergeSummary first = merge_stores(out, paths);
  const double merge_s = seconds_since(t);
  t = std::chrono::steady_clock::now();
  const MergeSummary again = merge_stores(out, paths);
  const double remerge_s = seconds_since(t);
  const std::uintmax_t merged_bytes = fs::file_size(dir / "merged.sqlite");

  std::cout << fmt::format(
      "runs={}\nshards={}\ncrossings_per_run={}\nwrite_shards_s={:.1f}\nshard_stores_mb={:.0f}\n"
      "merge_s={:.1f}\nmerge_runs_per_s={:.0f}\nadded={}\nremerge_s={:.1f}\nremerge_added={}\nremerge_identical={}\n"
      "merged_store_mb={:.0f}\nbytes_per_run={:.0f}\n",
      runs, shards, crossings, make_s, shard_bytes / 1e6, merge_s, runs / merge_s, first.added, remerge_s,
      again.added, again.identical, merged_bytes / 1e6, static_cast<double>(merged_bytes) / runs);
  fs::remove_all(dir);
  return first.added == runs && again.added == 0 && again.identical == runs ? 0 : 1;
}

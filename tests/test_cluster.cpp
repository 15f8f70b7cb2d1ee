// Studies on a cluster: shards (cover every job once, stable, balanced), merge (idempotent,
// conflicts refused, missing jobs listed, provenance kept), the packed record of MPI, and
// sharded + merged == local for a tiny study in both models. The MPI and Slurm end-to-end
// runs are script tests (tests/CMakeLists.txt, label slow).
#include "studies/jobs.hpp"
#include "studies/merge.hpp"
#include "studies/record_pack.hpp"
#include "studies/runner.hpp"
#include "studies/shard.hpp"
#include "studies/store.hpp"
#include "studies/study.hpp"
#include "tests/test_support.hpp"

#include <gtest/gtest.h>

#include <fmt/format.h>

#include <algorithm>
#include <map>
#include <random>
#include <sstream>

using namespace gapflow;
using gapflow::testing::source_path;
namespace fs = std::filesystem;

namespace {

struct TempDir : gapflow::testing::TempDir {
  TempDir() : gapflow::testing::TempDir("gapflow-cluster") {}
};

std::vector<Job> tiny_jobs() { return expand_jobs(load_study(source_path("studies/examples/tiny.toml"))); }

// n jobs with made-up keys and costs (no scenario needed to shard).
std::vector<Job> synthetic_jobs(int n, bool with_costs) {
  std::vector<Job> jobs(static_cast<std::size_t>(n));
  std::mt19937_64 rng(42);
  for (int i = 0; i < n; ++i) {
    jobs[i].id.key = fmt::format("{:016x}", rng());
    jobs[i].expected_cost = with_costs ? 1.0 + static_cast<double>(rng() % 1000) : 0.0;
  }
  return jobs;
}

// A record that depends on the job's key only: what a deterministic simulation gives.
RunRecord fake_record(const Job& job) {
  RunRecord r;
  r.model = job.id.model;
  r.scenario_name = "fake";
  r.scenario_hash = job.id.scenario_hash;
  r.run_seed = job.id.run_seed;
  r.replicate = job.id.replicate;
  r.particles = 60;
  r.passed = static_cast<int>(std::stoull(job.id.key, nullptr, 16) % 60);
  r.sim_time_s = 3.5;
  r.wall_time_s = 0.01 * (1 + job.id.replicate);
  r.j_paper = 10.0 + r.passed / 7.0;
  r.diameter_m = 0.00775, r.gap_m = 0.02;
  r.crossings = {{1, 0.5, 0.001}, {2, 0.75, -0.002}};
  r.avalanches = {{2, 0.5, 0.75, true, false}};
  r.clogs = {{0.75, 2.0, true, 0.01, false}};
  return r;
}

RunnerOptions fake_runner() {
  RunnerOptions o;
  o.run = [](const Job& job, const std::atomic<bool>*) { return fake_record(job); };
  return o;
}

// Run share I of K of `jobs` into its own store, as `gapflow study --shard I/K` does.
fs::path run_share(const TempDir& dir, const std::vector<Job>& jobs, ShardSpec shard, const RunnerOptions& o) {
  const fs::path db = dir / fmt::format("shard-{}-of-{}.sqlite", shard.index, shard.count);
  Store store(db);
  store.set_shard(shard.label());
  store.record_plan(plan_of(jobs, shard.count));
  run_jobs(jobs_of_shard(jobs, shard), store, o);
  return db;
}

}  // namespace

TEST(ClusterShard, SharesCoverEveryJobExactlyOnceForSeveralK) {
  const std::vector<Job> jobs = tiny_jobs();
  for (int k : {1, 2, 3, 5, 12, 13}) {
    std::map<std::string, int> seen;
    for (int i = 1; i <= k; ++i)
      for (const Job& j : jobs_of_shard(jobs, {i, k})) ++seen[j.id.key];
    EXPECT_EQ(seen.size(), jobs.size()) << "K = " << k;
    for (const auto& [key, n] : seen) EXPECT_EQ(n, 1) << key << " K = " << k;
  }
}

TEST(ClusterShard, PartitionIsStableUnderReplanningAndReordering) {
  const std::vector<Job> a = tiny_jobs();
  std::vector<Job> b = tiny_jobs();  // planned again
  std::reverse(b.begin(), b.end());
  std::map<std::string, int> share_a, share_b;
  const std::vector<int> sa = assign_shards(a, 5), sb = assign_shards(b, 5);
  for (std::size_t i = 0; i < a.size(); ++i) share_a[a[i].id.key] = sa[i], share_b[b[i].id.key] = sb[i];
  EXPECT_EQ(share_a, share_b);
}

TEST(ClusterShard, BalancesByExpectedCostAndDealsEqualJobsEvenly) {
  const std::vector<Job> jobs = synthetic_jobs(1000, true);
  const int k = 7;
  const std::vector<int> shard_of = assign_shards(jobs, k);
  std::vector<double> load(k, 0.0);
  double largest = 0;
  for (std::size_t i = 0; i < jobs.size(); ++i) {
    load[shard_of[i] - 1] += jobs[i].expected_cost;
    largest = std::max(largest, jobs[i].expected_cost);
  }
  const auto [lo, hi] = std::minmax_element(load.begin(), load.end());
  EXPECT_LE(*hi - *lo, largest) << "greedy longest-first: loads differ by at most one job";

  std::vector<int> count(k, 0);
  for (int s : assign_shards(synthetic_jobs(100, false), k)) ++count[s - 1];
  const auto [cmin, cmax] = std::minmax_element(count.begin(), count.end());
  EXPECT_LE(*cmax - *cmin, 1) << "jobs of unknown cost are dealt out evenly";
}

TEST(ClusterShard, ThreeDJobsCostMoreThanTwoD) {
  StudyDef study = parse_study("[study]\nname = \"c\"\nreplicates = 1\nmodels = [\"2d\", \"3d\"]\n"
                               "[[series]]\nlabel = \"a\"\nscenario = \"no_obstruction_medium.toml\"\n",
                               "c.toml", source_path("scenarios/paper"));
  const std::vector<Job> jobs = expand_jobs(study);
  ASSERT_EQ(jobs.size(), 2u);
  EXPECT_GT(jobs[0].expected_cost, 0);
  EXPECT_GT(jobs[1].expected_cost, 2 * jobs[0].expected_cost) << jobs[1].id.model;
}

TEST(ClusterShard, ParsesIOverKAndRejectsTheRest) {
  const ShardSpec s = parse_shard("3/8");
  EXPECT_EQ(s.index, 3);
  EXPECT_EQ(s.count, 8);
  EXPECT_EQ(s.label(), "3/8");
  for (const char* bad : {"0/3", "4/3", "3", "a/3", "1/0", "1/3x", "-1/3", ""}) {
    try {
      parse_shard(bad);
      ADD_FAILURE() << bad;
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find("1 <= I <= K"), std::string::npos) << e.what();
    }
  }
}

TEST(ClusterShard, PlanListsEveryJobWithItsShareAndScenario) {
  const std::vector<Job> jobs = tiny_jobs();
  std::ostringstream all, one;
  write_plan(all, jobs, 3);
  const ShardSpec second{2, 3};
  write_plan(one, jobs, 3, &second);
  const std::string a = all.str(), o = one.str();
  EXPECT_EQ(std::count(a.begin(), a.end(), '\n'), 12);
  EXPECT_EQ(std::count(o.begin(), o.end(), '\n'), static_cast<long>(jobs_of_shard(jobs, second).size()));
  EXPECT_NE(a.find("\"key\":\"" + jobs[0].id.key + "\""), std::string::npos);
  EXPECT_NE(a.find("\"run.replicate=1\""), std::string::npos);
  EXPECT_EQ(o.find("\"shard\":\"1/3\""), std::string::npos);
}

TEST(ClusterRecord, PackRoundTripsEveryFieldAndRejectsDamage) {
  Job job;
  job.id.key = "00000000000000ab";
  RunRecord r = fake_record(job);
  r.j_flowing = std::nullopt;
  r.clogs.push_back({1.0, 0.5, false, std::nullopt, std::nullopt});
  const std::string bytes = pack_record(r);
  const RunRecord back = unpack_record(bytes);
  EXPECT_EQ(pack_record(back), bytes);
  EXPECT_TRUE(same_results(back, r));
  EXPECT_EQ(back.wall_time_s, r.wall_time_s);
  EXPECT_FALSE(back.j_flowing.has_value());
  ASSERT_EQ(back.clogs.size(), 2u);
  EXPECT_FALSE(back.clogs[1].front_m.has_value());
  EXPECT_THROW(unpack_record(bytes.substr(0, bytes.size() - 1)), std::runtime_error);
  EXPECT_THROW(unpack_record(bytes + "x"), std::runtime_error);

  RunRecord slower = r;
  slower.wall_time_s *= 3;
  EXPECT_TRUE(same_results(slower, r)) << "wall time is not a result";
  RunRecord other = r;
  other.crossings[1].t = std::nextafter(other.crossings[1].t, 1.0);
  EXPECT_FALSE(same_results(other, r)) << "one ulp in one crossing is a different result";
}

TEST(ClusterMerge, MergesSharesIdempotentlyWithProvenance) {
  TempDir dir;
  const std::vector<Job> jobs = tiny_jobs();
  std::vector<fs::path> shards;
  for (int i = 1; i <= 3; ++i) shards.push_back(run_share(dir, jobs, {i, 3}, fake_runner()));
  Store local(dir / "local.sqlite");
  run_jobs(jobs, local, fake_runner());

  Store merged(dir / "merged.sqlite");
  const MergeSummary first = merge_stores(merged, shards);
  EXPECT_EQ(first.added, 12);
  EXPECT_EQ(first.identical, 0);
  EXPECT_TRUE(first.conflicts.empty());
  EXPECT_EQ(first.planned, 12);
  EXPECT_TRUE(first.missing.empty());
  EXPECT_TRUE(compare_stores(merged, local).empty());

  const MergeSummary again = merge_stores(merged, shards);
  EXPECT_EQ(again.added, 0);
  EXPECT_EQ(again.identical, 12);
  EXPECT_EQ(merged.count(), 12u);
  EXPECT_TRUE(compare_stores(merged, local).empty());

  const std::map<std::string, Provenance> p = merged.provenance();
  ASSERT_EQ(p.size(), 12u);
  const std::vector<Job> second = jobs_of_shard(jobs, {2, 3});
  const Provenance& q = p.at(second.front().id.key);
  EXPECT_EQ(q.shard, "2/3");
  EXPECT_EQ(q.code_version, code_version());
  EXPECT_FALSE(q.host.empty());
  EXPECT_EQ(fs::path(q.merged_from).filename(), "shard-2-of-3.sqlite");

  // Merged once more into another store: the provenance still names the share it was run in.
  Store twice(dir / "twice.sqlite");
  merge_stores(twice, {dir / "merged.sqlite"});
  EXPECT_EQ(twice.provenance().at(second.front().id.key).merged_from, q.merged_from);
}

TEST(ClusterMerge, AHalfFinishedSetSaysWhatIsMissing) {
  TempDir dir;
  const std::vector<Job> jobs = tiny_jobs();
  const fs::path one = run_share(dir, jobs, {1, 3}, fake_runner());
  Store merged(dir / "merged.sqlite");
  const MergeSummary m = merge_stores(merged, {one});
  EXPECT_EQ(m.planned, 12);
  std::vector<std::string> missing;
  for (const PlannedJob& p : m.missing) missing.push_back(p.id.key);
  std::vector<std::string> expected;
  for (int i : {2, 3})
    for (const Job& j : jobs_of_shard(jobs, {i, 3})) expected.push_back(j.id.key);
  std::sort(missing.begin(), missing.end());
  std::sort(expected.begin(), expected.end());
  EXPECT_EQ(missing, expected);
  EXPECT_THROW(merge_stores(merged, {dir / "no-such.sqlite"}), std::invalid_argument);

  // Share 2 dies half-way (its runs fail after the first two), then resumes; share 3 runs: complete.
  RunnerOptions dying = fake_runner();
  int calls = 0;
  dying.run = [&](const Job& job, const std::atomic<bool>*) {
    if (++calls > 2) throw std::runtime_error("node lost");
    return fake_record(job);
  };
  const fs::path two = run_share(dir, jobs, {2, 3}, dying);
  EXPECT_EQ(merge_stores(merged, {two}).missing.size(), expected.size() - 2);
  Store resumed(two);
  const RunnerSummary again = run_jobs(jobs_of_shard(jobs, {2, 3}), resumed, fake_runner());
  EXPECT_EQ(again.already_stored, 2);
  const MergeSummary done = merge_stores(merged, {one, two, run_share(dir, jobs, {3, 3}, fake_runner())});
  EXPECT_TRUE(done.missing.empty());
  EXPECT_EQ(merged.count(), jobs.size());
}

TEST(ClusterMerge, ConflictingResultsOrCodeVersionsAreReportedAndNotWritten) {
  TempDir dir;
  const std::vector<Job> jobs = tiny_jobs();
  const fs::path good = run_share(dir, jobs, {1, 1}, fake_runner());
  RunnerOptions different = fake_runner();
  different.run = [](const Job& job, const std::atomic<bool>*) {
    RunRecord r = fake_record(job);
    if (job.id.replicate == 1) r.passed += 1;
    return r;
  };
  const fs::path bad = dir / "bad.sqlite";
  {
    Store s(bad);
    run_jobs(jobs, s, different);
  }
  Store merged(dir / "merged.sqlite");
  merge_stores(merged, {good});
  const MergeSummary m = merge_stores(merged, {bad});
  EXPECT_EQ(m.conflicts.size(), 6u);  // replicate 1 of 6 points
  EXPECT_EQ(m.identical, 6);
  for (const MergeConflict& c : m.conflicts) EXPECT_EQ(c.what, "results differ") << c.key;
  EXPECT_TRUE(compare_stores(merged, Store(good)).empty()) << "the stored runs were kept";
  EXPECT_EQ(compare_stores(merged, Store(bad)).size(), 6u);

  // Same results from another build: reported as well.
  StoredRun run = Store(good).load().front();
  run.code_version = "0123abc";
  const fs::path other = dir / "other-build.sqlite";
  Store(other).import_runs({run}, {{"", "elsewhere", "0123abc", ""}});
  const MergeSummary v = merge_stores(merged, {other});
  ASSERT_EQ(v.conflicts.size(), 1u);
  EXPECT_NE(v.conflicts[0].what.find("code version differs"), std::string::npos) << v.conflicts[0].what;
}

// The real thing, small: 30 spheres for 1.5 s, one point, 2D and 3D, two replicates each.
TEST(ClusterMerge, ShardedAndMergedEqualsALocalRunInBothModels) {
  TempDir dir;
  const StudyDef study = parse_study(
      "[study]\nname = \"both\"\nreplicates = 2\nmodels = [\"2d\", \"3d\"]\nseed = 3\n"
      "set = [\"particles.count=30\", \"release.settle_s=0.2\", \"run.time_limit_s=1.5\"]\n"
      "[[series]]\nlabel = \"a\"\nscenario = \"no_obstruction_medium.toml\"\n",
      "both.toml", source_path("scenarios/paper"));
  const std::vector<Job> jobs = expand_jobs(study);
  ASSERT_EQ(jobs.size(), 4u);
  RunnerOptions o;
  o.workers = 2;
  Store local(dir / "local.sqlite");
  run_jobs(jobs, local, o);
  ASSERT_EQ(local.count(), 4u);
  std::vector<fs::path> shards;
  for (int i = 1; i <= 3; ++i) shards.push_back(run_share(dir, jobs, {i, 3}, o));
  Store merged(dir / "merged.sqlite");
  const MergeSummary m = merge_stores(merged, shards);
  EXPECT_TRUE(m.missing.empty());
  EXPECT_TRUE(m.conflicts.empty());
  const std::vector<std::string> differences = compare_stores(merged, local);
  EXPECT_TRUE(differences.empty()) << differences.front();
  std::set<std::string> models;
  for (const StoredRun& r : merged.load()) models.insert(r.id.model);
  EXPECT_EQ(models, (std::set<std::string>{"2d", "3d"}));
}

// Sequential replication (studies/sequential.hpp): the stopping rule, the coverage of the
// interval it ends with, the loader's keys, and the rounds run by the study runner
// (deterministic across worker counts, resumable, different counts for different points).
#include "common/random.hpp"
#include "studies/sequential.hpp"
#include "studies/study.hpp"
#include "tests/test_support.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <map>
#include <set>

using namespace gapflow;
using gapflow::testing::source_path;

namespace {

SequentialDef def(double target, int batch = 5) {
  SequentialDef d;
  d.enabled = true;
  d.target_halfwidth = target;
  d.batch = batch;
  return d;
}

struct SequentialOutcome {
  double coverage = 0;      // share of final Student-t 95 % intervals holding the true mean
  double mean_n = 0;        // replicates run, on average
  double share_capped = 0;  // studies that stopped at the cap
};

// `reps` synthetic points run through sequential_step exactly as the runner does: n0 values,
// then batches while the interval is too wide.
SequentialOutcome simulate(const std::function<double(RandomStream&)>& draw, double truth, int n0, int max,
                           const SequentialDef& d, int reps, std::uint64_t seed) {
  RandomStream rs(seed);
  SequentialOutcome o;
  for (int k = 0; k < reps; ++k) {
    std::vector<double> j;
    int n = n0;
    while (static_cast<int>(j.size()) < n) j.push_back(draw(rs));
    for (;;) {
      const SequentialStep s = sequential_step(j, n, max, d);
      if (s.next == n) break;
      while (static_cast<int>(j.size()) < s.next) j.push_back(draw(rs));
      n = s.next;
    }
    const Summary t = summarize(j);
    o.coverage += std::abs(t.mean - truth) <= t.ci95_half ? 1 : 0;
    o.mean_n += n;
    o.share_capped += n >= max ? 1 : 0;
  }
  o.coverage /= reps, o.mean_n /= reps, o.share_capped /= reps;
  return o;
}

}  // namespace

TEST(Sequential, StepAddsABatchUntilTheTargetOrTheCap) {
  const std::vector<double> tight(10, 10.0), wide{5, 15, 5, 15, 5, 15, 5, 15, 5, 15};
  EXPECT_TRUE(sequential_step(tight, 10, 40, def(0.02)).reached);
  EXPECT_EQ(sequential_step(tight, 10, 40, def(0.02)).next, 10);
  EXPECT_FALSE(sequential_step(wide, 10, 40, def(0.02)).reached);
  EXPECT_EQ(sequential_step(wide, 10, 40, def(0.02)).next, 15);
  EXPECT_EQ(sequential_step(wide, 38, 40, def(0.02)).next, 40) << "capped";
  EXPECT_EQ(sequential_step(wide, 40, 40, def(0.02)).next, 40);
  // Fewer than 2 runs with J: no interval, keep going.
  EXPECT_TRUE(std::isinf(sequential_step({10}, 10, 40, def(0.5)).relative_halfwidth));
  EXPECT_EQ(sequential_step({}, 10, 40, def(0.5)).next, 15);
}

// Optional stopping: coverage of the interval the rule ends with, over 4000 synthetic points
// (binomial sd 0.34 %). Stated tolerance: at least 93 % for normal and log-normal J (nominal
// 95 % minus 2 points); README "Sequential replication" quotes the figures.
TEST(Sequential, CoverageOfTheFinalIntervalStaysNearNominal) {
  const SequentialDef d = def(0.05);
  // Normal J, CV 0.2: about (1.96 x 0.2 / 0.05)^2 = 62 replicates needed.
  const SequentialOutcome normal =
      simulate([](RandomStream& rs) { return 10.0 * (1 + 0.2 * rs.normal()); }, 10.0, 10, 200, d, 4000, 41);
  EXPECT_GE(normal.coverage, 0.93) << "normal: mean n " << normal.mean_n;
  EXPECT_GT(normal.mean_n, 40);
  // Log-normal J, CV 0.3 (skewed).
  const double sigma = std::sqrt(std::log(1 + 0.09)), mean = 10.0;
  const SequentialOutcome lognormal = simulate(
      [&](RandomStream& rs) { return mean * std::exp(sigma * rs.normal() - 0.5 * sigma * sigma); }, mean, 10, 400, d,
      4000, 42);
  EXPECT_GE(lognormal.coverage, 0.93) << "log-normal: mean n " << lognormal.mean_n;
  // Clog-like: 10 % of the runs far below (a heavy lower tail). A sample of 10 without the rare
  // runs looks tight and stops: 74 % coverage. That is mostly the Student-t interval's own failure
  // at small n on such a law (a FIXED 10 covers 76 %), so what is asserted is that stopping costs
  // at most 3 points against running the minimum alone; README states the figures and the remedy
  // (a larger minimum: 30 gives 90 % here).
  auto clog_like = [](RandomStream& rs) {
    return rs.uniform() < 0.1 ? 10.0 * rs.uniform(0.3, 0.8) : 10.0 * (1 + 0.05 * rs.normal());
  };
  const double clog_truth = 0.9 * 10.0 + 0.1 * 5.5;
  const SequentialOutcome clogs = simulate(clog_like, clog_truth, 10, 400, d, 4000, 43);
  SequentialDef never = d;
  never.target_halfwidth = 1.0;  // reached at once: a fixed study of n0 runs
  const SequentialOutcome fixed10 = simulate(clog_like, clog_truth, 10, 400, never, 4000, 44);
  EXPECT_DOUBLE_EQ(fixed10.mean_n, 10.0);
  EXPECT_GE(clogs.coverage, fixed10.coverage - 0.03) << "clog-like: mean n " << clogs.mean_n;
  EXPECT_GE(simulate(clog_like, clog_truth, 30, 400, d, 4000, 45).coverage, 0.88) << "n0 = 30";
  std::printf("coverage: normal %.4f (mean n %.1f), log-normal %.4f (mean n %.1f), clog-like %.4f (mean n %.1f; "
              "fixed 10: %.4f)\n",
              normal.coverage, normal.mean_n, lognormal.coverage, lognormal.mean_n, clogs.coverage, clogs.mean_n,
              fixed10.coverage);
}

// ------------------------------------------------------------------ the study loader

namespace {

std::string seq_study(const std::string& keys) {
  return "[study]\nname = \"seq\"\n" + keys +
         "\n[[series]]\nlabel = \"a\"\nscenario = \"no_obstruction_medium.toml\"\n"
         "  [[series.sweep]]\n  key = \"bottleneck.gap_mm\"\n  values = [23.0, 38.75]\n";
}

StudyDef parse(const std::string& text) { return parse_study(text, "seq.toml", source_path("scenarios/paper")); }

ScenarioError error_of(const std::string& text) {
  try {
    parse(text);
  } catch (const ScenarioError& e) {
    return e;
  }
  ADD_FAILURE() << "no error for:\n" << text;
  return ScenarioError({}, "", "", "");
}

}  // namespace

TEST(Sequential, LoaderReadsTheKeys) {
  const StudyDef s = parse(seq_study(
      "replicates = 10\nreplicates_max = 30\nreplicates_batch = 4\nreplicates_target_halfwidth = 0.02"));
  EXPECT_TRUE(s.sequential.enabled);
  EXPECT_EQ(s.sequential.max_replicates, 30);
  EXPECT_EQ(s.sequential.batch, 4);
  EXPECT_DOUBLE_EQ(s.sequential.target_halfwidth, 0.02);
  EXPECT_EQ(max_replicates_for(s, ModelKind::box2d), 30);
  EXPECT_FALSE(apply_quick(s).sequential.enabled) << "--quick runs a fixed count";
  EXPECT_FALSE(parse(seq_study("replicates = 3")).sequential.enabled);
}

TEST(Sequential, LoaderRejectsBadValuesWithTheirPlace) {
  struct Case {
    std::string keys, key;
    int line;
  };
  const std::vector<Case> cases{
      {"replicates = 5\nreplicates_max = 30\nreplicates_target_halfwidth = 0.02", "study.replicates", 3},
      {"replicates_max = 30", "study.replicates_max", 3},
      {"replicates = 12\nreplicates_batch = 2", "study.replicates_batch", 4},
      {"replicates_target_halfwidth = 0.02", "study.replicates_max", 1},
      {"replicates = 12\nreplicates_max = 11\nreplicates_target_halfwidth = 0.02", "study.replicates_max", 4},
      {"replicates_max = 30\nreplicates_target_halfwidth = 0", "study.replicates_target_halfwidth", 4},
      {"replicates_max = 30\nreplicates_target_halfwidth = 1.5", "study.replicates_target_halfwidth", 4},
      {"replicates_max = 30\nreplicates_target_halfwidth = \"2 %\"", "study.replicates_target_halfwidth", 4},
      {"replicates_max = 30\nreplicates_batch = 0\nreplicates_target_halfwidth = 0.1", "study.replicates_batch", 4},
      {"replicates_max = 30\nreplicates_target_halfwidth = 0.1\n[per_model.2d]\nreplicates = 4",
       "per_model.2d.replicates", 6},
  };
  for (const Case& c : cases) {
    const ScenarioError e = error_of(seq_study(c.keys));
    EXPECT_EQ(e.key(), c.key) << c.keys << "\n" << e.what();
    if (c.line > 1) {
      EXPECT_EQ(e.where().line, c.line) << c.keys << "\n" << e.what();
    }
    EXPECT_EQ(e.where().source, "seq.toml");
  }
}

// ------------------------------------------------------------------ rounds in the runner

namespace {

// Stand-in runs: J drawn from the run's own seed, tight at the wide gap (CV 2 %), scattered at
// the narrow one (CV 30 %), so the two points need very different counts.
RunRecord fake_run(const Job& job) {
  RunRecord r;
  r.model = job.id.model;
  r.scenario_name = "fake";
  r.particles = r.passed = 60;
  r.diameter_m = 0.00775;
  RandomStream rs(job.id.run_seed);
  const double cv = job.id.point == 1 ? 0.02 : 0.3;
  r.j_paper = 10.0 * (1 + cv * rs.normal());
  return r;
}

struct Outcome {
  std::set<std::string> keys;
  std::map<int, int> runs_per_point;
  RunnerSummary summary;
};

Outcome run_study(const StudyDef& study, const std::filesystem::path& db, int workers,
                  const std::atomic<bool>* cancel = nullptr, std::function<void()> after_each = {}) {
  Store store(db);
  RunnerOptions o;
  o.workers = workers;
  o.cancel = cancel;
  o.run = [&](const Job& job, const std::atomic<bool>* c) {
    if (c && *c) throw RunCancelled();
    RunRecord r = fake_run(job);
    if (after_each) after_each();
    return r;
  };
  Outcome out;
  RunnerSummary first = run_jobs(expand_jobs(study), store, o);
  out.summary = first.cancelled ? first : run_sequential_rounds(study, store, o, first, JobRunner(run_jobs), nullptr);
  for (const StoredRun& r : store.load()) {
    out.keys.insert(r.id.key);
    out.runs_per_point[r.id.point] += 1;
  }
  return out;
}

}  // namespace

TEST(Sequential, RoundsDependOnSeedsNotOnWorkersAndResume) {
  gapflow::testing::TempDir dir("gapflow-sequential");
  const StudyDef study = parse(seq_study(
      "replicates = 10\nreplicates_max = 30\nreplicates_target_halfwidth = 0.05\nset = [\"particles.count=60\"]"));
  const Outcome one = run_study(study, dir.path() / "one.sqlite", 1);
  EXPECT_EQ(one.runs_per_point.at(1), 10) << "CV 2 %: +-5 % is reached at the minimum";
  EXPECT_EQ(one.runs_per_point.at(0), 30) << "CV 30 %: the cap";
  EXPECT_EQ(one.summary.done_now, 40);
  EXPECT_EQ(one.summary.total, 40);
  const Outcome three = run_study(study, dir.path() / "three.sqlite", 3);
  EXPECT_EQ(three.keys, one.keys);

  // Interrupted in the second round, then resumed: the same runs in the end.
  std::atomic<bool> cancel{false};
  std::atomic<int> done{0};
  const Outcome cut = run_study(study, dir.path() / "cut.sqlite", 2, &cancel, [&] {
    if (++done == 24) cancel = true;
  });
  EXPECT_TRUE(cut.summary.cancelled);
  EXPECT_LT(cut.keys.size(), one.keys.size());
  const Outcome resumed = run_study(study, dir.path() / "cut.sqlite", 2);
  EXPECT_EQ(resumed.keys, one.keys);
  EXPECT_EQ(resumed.summary.already_stored + resumed.summary.done_now, 40);
}

// End to end with real runs (studies/examples/tiny_sequential.toml, ~35 runs of 0.2 s): the two
// gaps stop at different counts, and running again finds everything done.
TEST(Sequential, TinyStudyStopsAtDifferentCountsPerPoint) {
  gapflow::testing::TempDir dir("gapflow-sequential");
  const StudyDef study = load_study(source_path("studies/examples/tiny_sequential.toml"));
  ASSERT_TRUE(study.sequential.enabled);
  Store store(dir / "runs.sqlite");
  RunnerOptions o;
  o.workers = 2;
  const RunnerSummary first = run_jobs(expand_jobs(study), store, o);
  ASSERT_EQ(first.done_now, 20);
  const RunnerSummary all = run_sequential_rounds(study, store, o, first, JobRunner(run_jobs), nullptr);
  EXPECT_TRUE(all.failed.empty());
  std::map<int, int> per_point;
  for (const StoredRun& r : store.load()) per_point[r.id.point] += 1;
  ASSERT_EQ(per_point.size(), 2u);
  EXPECT_NE(per_point[0], per_point[1]) << "the narrow gap scatters more and runs more";
  for (const auto& [point, n] : per_point) {
    EXPECT_GE(n, 10);
    EXPECT_LE(n, 20);
    EXPECT_EQ(n % 5, 0) << "minimum plus whole batches";
  }
  EXPECT_EQ(all.done_now, per_point[0] + per_point[1]);
  const RunnerSummary again = run_sequential_rounds(study, store, o, run_jobs(expand_jobs(study), store, o),
                                                    JobRunner(run_jobs), nullptr);
  EXPECT_EQ(again.done_now, 0) << "resumed: every round is found stored";
  EXPECT_EQ(again.already_stored, per_point[0] + per_point[1]);
}

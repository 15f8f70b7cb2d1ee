// The study runner and its results store: study loader, job expansion, SQLite
// round trip, determinism across worker counts, resume after kill -9, Ctrl-C.
// Simulations use studies/examples/tiny.toml (12 runs of 60 spheres, ~0.2 s each).
#include "common/text_file.hpp"
#include "studies/confirm.hpp"
#include "studies/jobs.hpp"
#include "studies/report.hpp"
#include "studies/runner.hpp"
#include "studies/store.hpp"
#include "studies/study.hpp"
#include "tests/test_support.hpp"

#include <gtest/gtest.h>

#include <fmt/format.h>
#include <sqlite3.h>

#include <algorithm>
#include <chrono>
#include <csignal>
#include <fcntl.h>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <spawn.h>
#include <sstream>
#include <sys/wait.h>
#include <thread>
#include <unistd.h>

extern char** environ;

using namespace gapflow;
using gapflow::testing::source_path;
namespace fs = std::filesystem;

namespace {

// ------------------------------------------------------------------ helpers

// A fresh folder per test (tests/test_support.hpp), named after this file's subject.
struct TempDir : gapflow::testing::TempDir {
  TempDir() : gapflow::testing::TempDir("gapflow-study") {}
};

fs::path tiny_study() { return source_path("studies/examples/tiny.toml"); }

// A study around the shipped medium scenario; `body` follows the [study] header lines.
std::string study_text(const std::string& study_keys, const std::string& rest) {
  return "[study]\nname = \"t\"\n" + study_keys + "\n[[series]]\nlabel = \"a\"\nscenario = \"no_obstruction_medium.toml\"\n" +
         rest;
}

StudyDef parse(const std::string& text) { return parse_study(text, "bad.toml", source_path("scenarios/paper")); }

// The error a study text (parsed, then expanded into jobs) raises.
ScenarioError study_error(const std::string& text) {
  try {
    expand_jobs(parse(text));
  } catch (const ScenarioError& e) {
    return e;
  }
  ADD_FAILURE() << "no error for:\n" << text;
  return ScenarioError({}, "", "", "");
}

// Every row of every run table as text, sorted; wall_time_s and finished_at left out
// (they are the only columns that may differ between two runs of the same jobs).
std::vector<std::string> dump(const fs::path& db_file) {
  sqlite3* db = nullptr;
  EXPECT_EQ(sqlite3_open_v2(db_file.c_str(), &db, SQLITE_OPEN_READONLY, nullptr), SQLITE_OK) << db_file;
  std::vector<std::string> rows;
  for (const std::string& table : Store::tables()) {
    // Which file was run, where and when, and a sharded study's job list: not run records.
    if (table == "study_files" || table == "provenance" || table == "plan") continue;
    sqlite3_stmt* s = nullptr;
    EXPECT_EQ(sqlite3_prepare_v2(db, ("SELECT * FROM " + table).c_str(), -1, &s, nullptr), SQLITE_OK);
    while (sqlite3_step(s) == SQLITE_ROW) {
      std::string row = table;
      for (int c = 0; c < sqlite3_column_count(s); ++c) {
        const std::string name = sqlite3_column_name(s, c);
        if (name == "wall_time_s" || name == "finished_at") continue;
        std::string value;
        switch (sqlite3_column_type(s, c)) {
          case SQLITE_NULL: value = "NULL"; break;
          case SQLITE_FLOAT: value = fmt::format("{}", sqlite3_column_double(s, c)); break;  // exact
          default: value = reinterpret_cast<const char*>(sqlite3_column_text(s, c));
        }
        row += " " + name + "=" + value;
      }
      rows.push_back(row);
    }
    sqlite3_finalize(s);
  }
  sqlite3_close(db);
  std::sort(rows.begin(), rows.end());
  return rows;
}

// The rows only one of two sorted dumps has (a readable failure message instead of two dumps).
std::string dump_difference(const std::vector<std::string>& a, const std::vector<std::string>& b) {
  std::vector<std::string> only_a, only_b;
  std::set_difference(a.begin(), a.end(), b.begin(), b.end(), std::back_inserter(only_a));
  std::set_difference(b.begin(), b.end(), a.begin(), a.end(), std::back_inserter(only_b));
  std::string text;
  for (std::size_t k = 0; k < std::min<std::size_t>(only_a.size(), 5); ++k) text += "\n  only in the first: " + only_a[k];
  for (std::size_t k = 0; k < std::min<std::size_t>(only_b.size(), 5); ++k) text += "\n  only in the second: " + only_b[k];
  return fmt::format("{} row(s) only in the first, {} only in the second{}", only_a.size(), only_b.size(), text);
}

// Number of rows of `runs`, or -1 while the file or table does not exist yet.
int stored_runs(const fs::path& db_file) {
  if (!fs::exists(db_file)) return -1;
  sqlite3* db = nullptr;
  int n = -1;
  if (sqlite3_open_v2(db_file.c_str(), &db, SQLITE_OPEN_READONLY, nullptr) == SQLITE_OK) {
    sqlite3_busy_timeout(db, 2000);
    sqlite3_stmt* s = nullptr;
    if (sqlite3_prepare_v2(db, "SELECT count(*) FROM runs", -1, &s, nullptr) == SQLITE_OK && sqlite3_step(s) == SQLITE_ROW)
      n = sqlite3_column_int(s, 0);
    sqlite3_finalize(s);
  }
  sqlite3_close(db);
  return n;
}

// `gapflow ARGS...` as a child process (stdout and stderr to `log`).
pid_t spawn_gapflow(std::vector<std::string> args, const fs::path& log) {
  const std::string binary = GAPFLOW_BINARY_DIR "/app/gapflow";
  args.insert(args.begin(), binary);
  std::vector<char*> argv;
  for (auto& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  posix_spawn_file_actions_t fa;
  posix_spawn_file_actions_init(&fa);
  posix_spawn_file_actions_addopen(&fa, STDOUT_FILENO, log.c_str(), O_WRONLY | O_CREAT | O_APPEND, 0644);
  posix_spawn_file_actions_adddup2(&fa, STDOUT_FILENO, STDERR_FILENO);
  pid_t pid = -1;
  const int rc = posix_spawn(&pid, binary.c_str(), &fa, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&fa);
  EXPECT_EQ(rc, 0) << "cannot start " << binary;
  return pid;
}

// `gapflow study` of the tiny study into `db`.
pid_t spawn_study(const fs::path& db, const fs::path& log, int jobs) {
  return spawn_gapflow({"study", tiny_study().string(), "--db", db.string(), "--jobs", std::to_string(jobs)}, log);
}

std::string read_log(const fs::path& log) {
  std::ifstream in(log);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

// Wait for the child; its exit code, or 128 + signal.
int wait_exit(pid_t pid) {
  int status = 0;
  waitpid(pid, &status, 0);
  return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
}

// Poll the store until at least `rows` runs are in it (false after 60 s or if the child ended).
bool wait_for_rows(const fs::path& db, int rows, pid_t pid) {
  const auto give_up = std::chrono::steady_clock::now() + std::chrono::seconds(60);
  while (std::chrono::steady_clock::now() < give_up) {
    if (stored_runs(db) >= rows) return true;
    int status = 0;
    if (waitpid(pid, &status, WNOHANG) == pid) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  return false;
}

RunnerSummary run_tiny(const fs::path& db, int workers) {
  const std::vector<Job> jobs = expand_jobs(load_study(tiny_study()));
  Store store(db);
  RunnerOptions o;
  o.workers = workers;
  return run_jobs(jobs, store, o);
}

// A record with every field set and child rows of each kind.
RunRecord sample_record() {
  RunRecord r;
  r.model = "3d";
  r.scenario_name = "sample";
  r.scenario_hash = 0xfedcba9876543210ull;
  r.base_seed = 42;
  r.replicate = 3;
  r.run_seed = 0x8000000000000001ull;  // top bit set: must survive SQLite's signed integers and hex text
  r.time_step_s = 0.002;
  r.diameter_m = 0.00775, r.gap_m = 0.033, r.distance_m = 0.1, r.incline_rad = 0.13962634015954636;
  r.particles = 5, r.passed = 5, r.reinjected = 1, r.perturbations = 2, r.escaped = 0, r.max_conservation_error = 0;
  r.sim_time_s = 12.345678901234567, r.wall_time_s = 1.5;
  r.end_reason = EndReason::time_limit;
  r.regime = Regime::intermittent;
  r.j_paper = std::nullopt;
  r.j_flowing = 1.0 / 3.0;
  r.j_mid = 0.1 + 0.2;
  r.crossings = {{3, 0.5, -0.001}, {0, 0.75, 0.002}, {4, 2.5, 0.0}, {1, 2.6, 1e-17}, {3, 2.7, 0.001}};  // 3 re-injected
  r.avalanches = {{2, 0.5, 0.75, true, false}, {2, 2.5, 2.6, false, true}};
  // Located on the obstruction, located elsewhere (false must not read back as NULL), not located.
  r.clogs = {{0.75, 1.75, false, 0.0171234567890123, true}, {1.9, 1.25, false, 0.005, false},
             {2.6, 9.745678901234567, true}};
  return r;
}

void expect_same_record(const RunRecord& a, const RunRecord& b) {
  EXPECT_EQ(a.model, b.model);
  EXPECT_EQ(a.scenario_name, b.scenario_name);
  EXPECT_EQ(a.scenario_hash, b.scenario_hash);
  EXPECT_EQ(a.base_seed, b.base_seed);
  EXPECT_EQ(a.replicate, b.replicate);
  EXPECT_EQ(a.run_seed, b.run_seed);
  EXPECT_EQ(a.time_step_s, b.time_step_s);
  EXPECT_EQ(a.diameter_m, b.diameter_m);
  EXPECT_EQ(a.gap_m, b.gap_m);
  EXPECT_EQ(a.distance_m, b.distance_m);
  EXPECT_EQ(a.incline_rad, b.incline_rad);
  EXPECT_EQ(a.particles, b.particles);
  EXPECT_EQ(a.passed, b.passed);
  EXPECT_EQ(a.reinjected, b.reinjected);
  EXPECT_EQ(a.perturbations, b.perturbations);
  EXPECT_EQ(a.escaped, b.escaped);
  EXPECT_EQ(a.max_conservation_error, b.max_conservation_error);
  EXPECT_EQ(a.sim_time_s, b.sim_time_s);
  EXPECT_EQ(a.wall_time_s, b.wall_time_s);
  EXPECT_EQ(a.end_reason, b.end_reason);
  EXPECT_EQ(a.regime, b.regime);
  EXPECT_EQ(a.j_paper, b.j_paper);
  EXPECT_EQ(a.j_flowing, b.j_flowing);
  EXPECT_EQ(a.j_mid, b.j_mid);
  ASSERT_EQ(a.crossings.size(), b.crossings.size());
  for (std::size_t i = 0; i < a.crossings.size(); ++i) {
    EXPECT_EQ(a.crossings[i].id, b.crossings[i].id) << i;
    EXPECT_EQ(a.crossings[i].t, b.crossings[i].t) << i;
    EXPECT_EQ(a.crossings[i].x, b.crossings[i].x) << i;
  }
  ASSERT_EQ(a.avalanches.size(), b.avalanches.size());
  for (std::size_t i = 0; i < a.avalanches.size(); ++i) {
    EXPECT_EQ(a.avalanches[i].size, b.avalanches[i].size) << i;
    EXPECT_EQ(a.avalanches[i].t_start, b.avalanches[i].t_start) << i;
    EXPECT_EQ(a.avalanches[i].t_end, b.avalanches[i].t_end) << i;
    EXPECT_EQ(a.avalanches[i].first, b.avalanches[i].first) << i;
    EXPECT_EQ(a.avalanches[i].censored, b.avalanches[i].censored) << i;
  }
  ASSERT_EQ(a.clogs.size(), b.clogs.size());
  for (std::size_t i = 0; i < a.clogs.size(); ++i) {
    EXPECT_EQ(a.clogs[i].t_start, b.clogs[i].t_start) << i;
    EXPECT_EQ(a.clogs[i].duration, b.clogs[i].duration) << i;
    EXPECT_EQ(a.clogs[i].censored, b.clogs[i].censored) << i;
    EXPECT_EQ(a.clogs[i].front_m, b.clogs[i].front_m) << i;
    EXPECT_EQ(a.clogs[i].on_obstruction, b.clogs[i].on_obstruction) << i;
  }
}

JobIdentity sample_identity() {
  JobIdentity id;
  id.key = "0123456789abcdef";
  id.study = "s";
  id.series = "cylinder";
  id.point = 2;
  id.point_label = "obstruction.distance_mm=90.0, obstruction.shape=\"cylinder\"";
  id.axes_json = R"({"obstruction.distance_mm":90.0,"obstruction.shape":"cylinder"})";
  id.model = "3d";
  id.replicate = 3;
  id.base_seed = 42;
  id.run_seed = 0x8000000000000001ull;
  id.scenario_hash = 0xfedcba9876543210ull;
  return id;
}

}  // namespace

// ------------------------------------------------------------------ study loader

TEST(StudyLoader, ReadsTheTinyStudy) {
  const StudyDef s = load_study(tiny_study());
  EXPECT_EQ(s.name, "tiny");
  EXPECT_EQ(s.replicates, 2);
  EXPECT_EQ(s.models, std::vector<ModelKind>{ModelKind::box2d});
  EXPECT_EQ(s.seed, 7u);
  EXPECT_EQ(s.set.size(), 5u);
  ASSERT_EQ(s.series.size(), 2u);
  EXPECT_EQ(s.series[0].label, "gap");
  EXPECT_TRUE(fs::exists(s.series[0].scenario)) << "scenario resolved against the study file's folder";
  ASSERT_EQ(s.series[0].axes.size(), 1u);
  EXPECT_EQ(s.series[0].axes[0].values.size(), 3u);
  EXPECT_EQ(s.series[0].axes[0].values[0].toml, "19.4");  // shortest round-trip text
  ASSERT_EQ(s.series[1].axes.size(), 1u);
  std::vector<std::string> incline;
  for (const AxisValue& v : s.series[1].axes[0].values) incline.push_back(v.toml);
  EXPECT_EQ(incline, (std::vector<std::string>{"6", "8", "10"})) << "from/to/step of integers stays integer";
  EXPECT_EQ(s.quick.replicates, 1);
  EXPECT_EQ(s.quick.thin, 2);
}

TEST(StudyLoader, FloatRangeIsInclusiveAndRounded) {
  const StudyDef s = parse(study_text("", "[[series.sweep]]\nkey = \"obstruction.distance_mm\"\nfrom = 0.1\nto = 0.5\nstep = 0.1\n"));
  std::vector<std::string> v;
  for (const AxisValue& a : s.series[0].axes[0].values) v.push_back(a.toml);
  EXPECT_EQ(v, (std::vector<std::string>{"0.1", "0.2", "0.3", "0.4", "0.5"}));
}

TEST(StudyLoader, RejectsUnknownKeyWithLine) {
  const ScenarioError e = study_error(study_text("replicate = 3", ""));
  EXPECT_EQ(e.key(), "study.replicate");
  EXPECT_EQ(e.where().line, 3);
  EXPECT_NE(std::string(e.what()).find("allowed in [study]"), std::string::npos) << e.what();
}

TEST(StudyLoader, RejectsUnknownKeyInSweepAndUnknownSection) {
  ScenarioError e = study_error(study_text("", "[[series.sweep]]\nkey = \"plane.incline_deg\"\nvalue = [1]\n"));
  EXPECT_EQ(e.key(), "series.sweep.value");
  EXPECT_EQ(e.where().line, 9);
  e = study_error(study_text("", "[reprot]\nx = 1\n"));
  EXPECT_EQ(e.key(), "reprot");
}

TEST(StudyLoader, RejectsAnEmptyQuickTable) {
  // [quick] with nothing in it would run the full study under --quick's name.
  const ScenarioError e = study_error(study_text("", "[quick]\n"));
  EXPECT_EQ(e.key(), "quick.replicates");
  EXPECT_EQ(e.where().line, 7);
  EXPECT_NE(std::string(e.what()).find("must set replicates, models or thin"), std::string::npos) << e.what();
}

TEST(StudyLoader, RejectsBadModelsEntry) {
  const ScenarioError e = study_error(study_text("models = [\"2d\", \"4d\"]", ""));
  EXPECT_EQ(e.key(), "study.models");
  EXPECT_EQ(e.value(), "\"4d\"");
  EXPECT_EQ(e.where().line, 3);
  EXPECT_EQ(study_error(study_text("models = []", "")).key(), "study.models");
  EXPECT_EQ(study_error(study_text("models = [\"2d\", \"2d\"]", "")).key(), "study.models");
}

TEST(StudyLoader, RejectsZeroReplicates) {
  const ScenarioError e = study_error(study_text("replicates = 0", ""));
  EXPECT_EQ(e.key(), "study.replicates");
  EXPECT_EQ(e.where().line, 3);
  EXPECT_EQ(study_error("[study]\nname = \"t\"\n[quick]\nthin = 0\n[[series]]\nlabel=\"a\"\nscenario=\"x.toml\"\n").key(),
            "quick.thin");
}

TEST(StudyLoader, RejectsEmptyValuesAndMixedRanges) {
  ScenarioError e = study_error(study_text("", "[[series.sweep]]\nkey = \"plane.incline_deg\"\nvalues = []\n"));
  EXPECT_EQ(e.key(), "series.sweep.values");
  EXPECT_EQ(e.where().line, 9);
  e = study_error(study_text("", "[[series.sweep]]\nkey = \"plane.incline_deg\"\nvalues = [1]\nfrom = 1\n"));
  EXPECT_EQ(e.key(), "series.sweep.values");
  e = study_error(study_text("", "[[series.sweep]]\nkey = \"plane.incline_deg\"\nfrom = 5\nto = 1\nstep = 1\n"));
  EXPECT_EQ(e.key(), "series.sweep.to");
}

TEST(StudyLoader, RejectsSeedAndReplicateOverrides) {
  EXPECT_EQ(study_error(study_text("set = [\"run.seed=3\"]", "")).key(), "study.set");
  EXPECT_EQ(study_error(study_text("", "[[series.sweep]]\nkey = \"run.replicate\"\nvalues = [1, 2]\n")).key(),
            "series.sweep.key");
}

TEST(StudyLoader, RejectsDuplicateLabelAndMissingParts) {
  EXPECT_EQ(study_error(study_text("", "[[series]]\nlabel = \"a\"\nscenario = \"x.toml\"\n")).key(), "series.label");
  EXPECT_EQ(study_error("[study]\nname = \"t\"\n").key(), "series");
  EXPECT_EQ(study_error("[[series]]\nlabel = \"a\"\nscenario = \"x.toml\"\n").key(), "study");
}

TEST(StudyLoader, BadSweepKeyIsTheScenarioLoadersErrorAtTheStudyValue) {
  const ScenarioError e =
      study_error(study_text("", "[[series.sweep]]\nkey = \"obstruction.distanse_mm\"\nvalues = [70, 80]\n"));
  EXPECT_EQ(e.key(), "obstruction.distanse_mm");
  EXPECT_EQ(e.where().source, "bad.toml");
  EXPECT_EQ(e.where().line, 9) << e.what();
  EXPECT_NE(std::string(e.what()).find("unknown key"), std::string::npos) << e.what();
  EXPECT_NE(std::string(e.what()).find("series 'a'"), std::string::npos) << e.what();
}

TEST(StudyLoader, BadSweepValueIsLocatedAtThatValue) {
  const ScenarioError e =
      study_error(study_text("", "[[series.sweep]]\nkey = \"bottleneck.gap_mm\"\nvalues = [30,\n  -4]\n"));
  EXPECT_EQ(e.key(), "bottleneck.gap_mm");
  EXPECT_EQ(e.where().line, 10) << e.what();
  EXPECT_EQ(e.where().column, 3) << e.what();
  EXPECT_NE(std::string(e.what()).find("bottleneck.gap_mm=-4"), std::string::npos) << "names the point: " << e.what();
}

TEST(StudyLoader, BadSetStringIsLocatedInTheStudy) {
  const ScenarioError e = study_error(study_text("set = [\"run.time_limit_s=300\", \"particles.count=0\"]", ""));
  EXPECT_EQ(e.key(), "particles.count");
  EXPECT_EQ(e.where().source, "bad.toml");
  EXPECT_EQ(e.where().line, 3);
}

// ------------------------------------------------------------------ jobs

TEST(StudyJobs, GridIsTheCartesianProductInOrder) {
  const StudyDef s = parse(study_text("replicates = 2\nmodels = [\"2d\", \"3d\"]\nset = [\"particles.count=20\"]",
                                      "[[series.sweep]]\nkey = \"bottleneck.gap_mm\"\nvalues = [30, 35, 40]\n"
                                      "[[series.sweep]]\nkey = \"particles.restitution\"\nvalues = [0.1, 0.5]\n"));
  const std::vector<Job> jobs = expand_jobs(s);
  ASSERT_EQ(jobs.size(), 3u * 2u * 2u * 2u);
  // series, point, model, replicate: replicate fastest, then model, then the last axis.
  EXPECT_EQ(jobs[0].id.point_label, "bottleneck.gap_mm=30, particles.restitution=0.1");
  EXPECT_EQ(jobs[0].id.axes_json, R"({"bottleneck.gap_mm":30,"particles.restitution":0.1})");
  EXPECT_EQ(jobs[1].id.replicate, 1);
  EXPECT_EQ(jobs[2].id.model, "3d");
  EXPECT_EQ(jobs[4].id.point, 1);
  EXPECT_EQ(jobs[4].id.point_label, "bottleneck.gap_mm=30, particles.restitution=0.5");
  EXPECT_EQ(jobs[8].id.point_label, "bottleneck.gap_mm=35, particles.restitution=0.1");
  EXPECT_EQ(jobs.back().id.point, 5);
  EXPECT_EQ(jobs[0].overrides.back(), "run.replicate=0");
  EXPECT_EQ(jobs[0].overrides[jobs[0].overrides.size() - 2], "run.seed=1");
}

// [per_model]: the 3D model runs fewer replicates on every other value; its points keep
// their full-grid indices, so 2D and 3D line up point by point.
TEST(StudyJobs, PerModelPlanThinsAndCutsReplicatesOfThatModelOnly) {
  const StudyDef s = parse(study_text("replicates = 3\nmodels = [\"2d\", \"3d\"]\nset = [\"particles.count=20\"]",
                                      "[[series.sweep]]\nkey = \"bottleneck.gap_mm\"\nvalues = [30, 35, 40, 45, 50]\n"
                                      "[per_model.3d]\nreplicates = 1\nthin = 2\n"));
  const std::vector<Job> jobs = expand_jobs(s);
  std::vector<int> points_3d;
  int runs_2d = 0;
  for (const Job& j : jobs) (j.id.model == "3d" ? points_3d.push_back(j.id.point) : void(++runs_2d));
  EXPECT_EQ(runs_2d, 5 * 3);
  EXPECT_EQ(points_3d, (std::vector<int>{0, 2, 4}));
  EXPECT_EQ(expand_jobs(apply_quick(s)).size(), 5u * 2u * 3u) << "--quick has one budget for every model";
  const ScenarioError e = [] {
    try {
      parse(study_text("", "[per_model.4d]\nreplicates = 1\n"));
    } catch (const ScenarioError& e) {
      return e;
    }
    return ScenarioError({}, "", "", "");
  }();
  EXPECT_EQ(e.key(), "per_model.4d");
  EXPECT_EQ(e.where().line, 7);
}

// [per_model.2d] set: a 2D-only reduced-model effect changes the 2D jobs only, so the 3D
// runs keep their keys (and a store made without it still holds them).
TEST(StudyJobs, PerModelSetChangesThatModelsJobsOnly) {
  const std::string sweep = "[[series.sweep]]\nkey = \"bottleneck.gap_mm\"\nvalues = [30, 35]\n";
  const std::string head = "replicates = 1\nmodels = [\"2d\", \"3d\"]\nset = [\"particles.count=20\"]";
  const std::vector<Job> plain = expand_jobs(parse(study_text(head, sweep)));
  const std::vector<Job> with = expand_jobs(parse(study_text(
      head, sweep + "[per_model.2d]\nset = [\"model.box2d.rolling.enabled=true\", \"model.box2d.rolling_contact=1\"]\n")));
  ASSERT_EQ(plain.size(), with.size());
  for (std::size_t i = 0; i < plain.size(); ++i) {
    ASSERT_EQ(plain[i].id.model, with[i].id.model);
    if (plain[i].id.model == "3d") EXPECT_EQ(plain[i].id.key, with[i].id.key) << i;
    else EXPECT_NE(plain[i].id.key, with[i].id.key) << i;
  }
  // --quick keeps the effect (only replicates and thinning are the quick budget's).
  const std::vector<Job> quick = expand_jobs(apply_quick(parse(study_text(
      head, sweep + "[per_model.2d]\nset = [\"model.box2d.rolling_contact=1\"]\n[quick]\nreplicates = 1\n"))));
  for (const Job& j : quick) {
    if (j.id.model != "2d") continue;
    EXPECT_EQ(std::count(j.overrides.begin(), j.overrides.end(), "model.box2d.rolling_contact=1"), 1) << j.id.key;
  }
  const ScenarioError e = study_error(study_text(head, sweep + "[per_model.2d]\nset = [\"model.box2d.rolling_contact=7\"]\n"));
  EXPECT_EQ(e.key(), "model.box2d.rolling_contact") << e.what();
  EXPECT_EQ(e.where().line, 13) << e.what();
}

// Screen ranking: a point must have J in every screening run to outrank one that has;
// the confirming jobs carry [confirm] set after the study's overrides.
TEST(StudyConfirm, RanksCompletePointsFirstAndAppliesConfirmSet) {
  const StudyDef s = parse(study_text("replicates = 2\nset = [\"particles.count=20\", \"run.time_limit_s=25\"]",
                                      "[[series.sweep]]\nkey = \"bottleneck.gap_mm\"\nvalues = [30, 35, 40]\n"
                                      "[confirm]\ntop = 1\nreplicates = 1\nset = [\"run.time_limit_s=60\"]\n"));
  std::vector<StoredRun> runs;
  auto add = [&](int point, std::optional<double> j) {
    StoredRun r;
    r.id.study = "t", r.id.series = "a", r.id.model = "2d", r.id.point = point;
    r.record.j_paper = j;
    runs.push_back(r);
  };
  add(0, 90.0), add(0, 92.0);          // complete, mean 91
  add(1, 120.0), add(1, std::nullopt);  // one lucky run: must not win
  add(2, 80.0), add(2, 84.0);          // complete, mean 82
  const std::vector<RankedPoint> ranked = rank_screened_points(s, runs);
  ASSERT_EQ(ranked.size(), 3u);
  EXPECT_EQ(ranked[0].point, 0);
  EXPECT_EQ(ranked[1].point, 2);
  EXPECT_EQ(ranked[2].point, 1);
  EXPECT_EQ(ranked[2].runs_with_j, 1);
  std::vector<Job> jobs = confirm_jobs(s, ranked);
  ASSERT_EQ(jobs.size(), 1u);
  EXPECT_EQ(jobs[0].id.model, "3d");
  EXPECT_EQ(jobs[0].id.point, 0);
  StudyDef with_baseline = s;
  with_baseline.report.baseline = "a";  // every point of the baseline series is confirmed, none is a candidate
  EXPECT_EQ(confirm_jobs(with_baseline, ranked).size(), 3u);
  // The baseline ranked first does not take a candidate's place.
  const StudyDef two = parse(study_text("replicates = 1\nset = [\"particles.count=20\"]",
                                        "[[series.sweep]]\nkey = \"bottleneck.gap_mm\"\nvalues = [30, 35]\n"
                                        "[[series]]\nlabel = \"base\"\nscenario = \"no_obstruction_medium.toml\"\n"
                                        "[confirm]\ntop = 1\nreplicates = 1\n[report]\nbaseline = \"base\"\n"));
  std::vector<RankedPoint> order(3);
  order[0].series = "base", order[1].series = "a", order[1].point = 1, order[2].series = "a";
  std::set<std::pair<std::string, int>> picked;
  for (const Job& j : confirm_jobs(two, order)) picked.insert({j.id.series, j.id.point});
  EXPECT_EQ(picked, (std::set<std::pair<std::string, int>>{{"base", 0}, {"a", 1}}));
  const auto& o = jobs[0].overrides;
  const auto at = [&](const std::string& text) { return std::find(o.begin(), o.end(), text) - o.begin(); };
  EXPECT_LT(at("run.time_limit_s=25"), at("run.time_limit_s=60")) << "the confirm override comes last and wins";
  EXPECT_LT(at("run.time_limit_s=60"), static_cast<std::ptrdiff_t>(o.size()));
  EXPECT_DOUBLE_EQ(compile_job(jobs[0]).def.run.time_limit_s, 60.0);
  // A confirming model with its own [per_model] set keeps it, and [confirm] set still comes last.
  const StudyDef own = parse(study_text("replicates = 2\nset = [\"particles.count=20\", \"run.time_limit_s=25\"]",
                                        "[[series.sweep]]\nkey = \"bottleneck.gap_mm\"\nvalues = [30, 35, 40]\n"
                                        "[per_model.3d]\nreplicates = 1\nset = [\"run.time_limit_s=30\"]\n"
                                        "[confirm]\ntop = 1\nreplicates = 2\nset = [\"run.time_limit_s=60\"]\n"));
  const std::vector<Job> own_jobs = confirm_jobs(own, ranked);
  ASSERT_EQ(own_jobs.size(), 2u) << "[confirm] replicates, not the model's";
  const auto& p = own_jobs[0].overrides;
  const auto pos = [&](const std::string& text) { return std::find(p.begin(), p.end(), text) - p.begin(); };
  EXPECT_LT(pos("run.time_limit_s=30"), pos("run.time_limit_s=60"));
  EXPECT_LT(pos("run.time_limit_s=60"), static_cast<std::ptrdiff_t>(p.size()));
  EXPECT_DOUBLE_EQ(compile_job(own_jobs[0]).def.run.time_limit_s, 60.0);
}

TEST(StudyJobs, ThinKeepsFirstAndLast) {
  std::vector<AxisValue> values;
  for (int i = 0; i < 7; ++i) values.push_back({std::to_string(i), std::to_string(i), {}});
  auto text = [](const std::vector<AxisValue>& v) {
    std::string s;
    for (const AxisValue& a : v) s += a.toml;
    return s;
  };
  EXPECT_EQ(text(thin_values(values, 3)), "036");
  values.pop_back();
  EXPECT_EQ(text(thin_values(values, 3)), "035");
  EXPECT_EQ(text(thin_values(values, 1)), "012345");
  EXPECT_EQ(text(thin_values(values, 100)), "05");
  const StudyDef quick = apply_quick(load_study(tiny_study()));
  EXPECT_EQ(quick.replicates, 1);
  EXPECT_EQ(expand_jobs(quick).size(), 4u);  // 2 series x (first, last) x 1 replicate
}

TEST(StudyJobs, KeysAreStableUniqueAndFollowTheScenario) {
  const std::vector<Job> a = expand_jobs(load_study(tiny_study()));
  const std::vector<Job> b = expand_jobs(load_study(tiny_study()));
  ASSERT_EQ(a.size(), 12u);
  std::set<std::string> keys;
  for (std::size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(a[i].id.key, b[i].id.key);
    EXPECT_EQ(a[i].id.key.size(), 16u);
    EXPECT_EQ(a[i].id.key.find_first_not_of("0123456789abcdef"), std::string::npos);
    EXPECT_EQ(a[i].id.key, job_key(a[i].id.scenario_hash, a[i].model));
    keys.insert(a[i].id.key);
  }
  EXPECT_EQ(keys.size(), a.size());
  // The key is the resolved scenario's: the same job from a differently written file has the same key.
  const Job& first = a[0];
  const CompiledScenario sc = compile_job(first);
  EXPECT_EQ(first.id.key, job_key(scenario_hash(sc.def), ModelKind::box2d));
  EXPECT_NE(first.id.key, job_key(first.id.scenario_hash, ModelKind::bullet));

  // Change one sweep value: only that point's keys change.
  StudyDef changed = load_study(tiny_study());
  changed.series[0].axes[0].values[1].toml = "23.5";
  const std::vector<Job> c = expand_jobs(changed);
  for (std::size_t i = 0; i < a.size(); ++i) {
    const bool moved = a[i].id.series == "gap" && a[i].id.point == 1;
    EXPECT_EQ(a[i].id.key != c[i].id.key, moved) << i;
  }
}

TEST(StudyJobs, DuplicatePointsAreRejected) {
  const ScenarioError e =
      study_error(study_text("", "[[series.sweep]]\nkey = \"bottleneck.gap_mm\"\nvalues = [30, 30.0]\n"));
  EXPECT_NE(std::string(e.what()).find("same scenario"), std::string::npos) << e.what();
}

// ------------------------------------------------------------------ store

TEST(StudyStore, RoundTripsARecordWithChildRows) {
  TempDir dir;
  const RunRecord r = sample_record();
  const JobIdentity id = sample_identity();
  {
    Store store(dir / "runs.sqlite");
    EXPECT_FALSE(store.has(id.key));
    store.put(id, r);
    EXPECT_THROW(store.put(id, r), std::runtime_error) << "a key is stored once";
  }
  Store store(dir / "runs.sqlite");  // reopened: the schema is not recreated
  EXPECT_TRUE(store.has(id.key));
  EXPECT_EQ(store.count(), 1u);
  const std::vector<StoredRun> runs = store.load("s");
  ASSERT_EQ(runs.size(), 1u);
  expect_same_record(runs[0].record, r);
  EXPECT_EQ(runs[0].id.key, id.key);
  EXPECT_EQ(runs[0].id.series, id.series);
  EXPECT_EQ(runs[0].id.point, id.point);
  EXPECT_EQ(runs[0].id.point_label, id.point_label);
  EXPECT_EQ(runs[0].id.axes_json, id.axes_json);
  EXPECT_EQ(runs[0].id.run_seed, id.run_seed);
  EXPECT_EQ(runs[0].code_version, code_version());
  EXPECT_FALSE(runs[0].finished_at.empty());
  EXPECT_TRUE(store.load("other").empty());
}

// A store written before clogs were located (no front_m, no on_obstruction column), or
// before on_obstruction alone, stays readable, and gets the columns when next written to.
namespace {
void expect_older_store_reads_back(const std::vector<std::string>& dropped_columns) {
  TempDir dir;
  JobIdentity old_id = sample_identity();
  {
    Store store(dir / "runs.sqlite");
    store.put(old_id, sample_record());
  }
  {
    sqlite3* db = nullptr;
    ASSERT_EQ(sqlite3_open((dir / "runs.sqlite").c_str(), &db), SQLITE_OK);
    for (const std::string& column : dropped_columns)
      ASSERT_EQ(sqlite3_exec(db, ("ALTER TABLE clogs DROP COLUMN " + column).c_str(), nullptr, nullptr, nullptr),
                SQLITE_OK);
    sqlite3_close(db);
  }
  const bool front_kept = dropped_columns.size() == 1;
  Store store(dir / "runs.sqlite");
  std::vector<StoredRun> runs = store.load("s");
  ASSERT_EQ(runs.size(), 1u);
  ASSERT_EQ(runs[0].record.clogs.size(), 3u);
  EXPECT_EQ(runs[0].record.clogs[0].front_m.has_value(), front_kept);
  EXPECT_FALSE(runs[0].record.clogs[0].on_obstruction) << "not measured then";
  JobIdentity new_id = sample_identity();
  new_id.key = "fedcba9876543210";
  store.put(new_id, sample_record());
  runs = store.load("s");
  ASSERT_EQ(runs.size(), 2u);
  const RunRecord& fresh = runs[0].id.key == new_id.key ? runs[0].record : runs[1].record;
  const RunRecord& old = runs[0].id.key == new_id.key ? runs[1].record : runs[0].record;
  expect_same_record(fresh, sample_record());
  EXPECT_EQ(old.clogs[0].front_m.has_value(), front_kept);
  EXPECT_FALSE(old.clogs[0].on_obstruction);
}
}  // namespace

TEST(StudyStore, ReadsClogsWithoutAFrontFromAStoreWrittenBeforeIt) {
  expect_older_store_reads_back({"on_obstruction", "front_m"});
}

TEST(StudyStore, ReadsClogsWithAFrontButNoObstructionContactFromAStoreWrittenBeforeIt) {
  expect_older_store_reads_back({"on_obstruction"});
}

TEST(StudyStore, ExportsCsvWithQuotingAndNulls) {
  TempDir dir;
  Store store(dir / "runs.sqlite");
  store.put(sample_identity(), sample_record());
  std::ostringstream runs, crossings;
  store.export_csv("runs", runs);
  store.export_csv("crossings", crossings);
  EXPECT_EQ(runs.str().rfind("job_key,study,series,point,point_label,axes_json,", 0), 0u) << runs.str();
  EXPECT_NE(runs.str().find(R"("{""obstruction.distance_mm"":90.0,""obstruction.shape"":""cylinder""}")"),
            std::string::npos)
      << runs.str();
  EXPECT_NE(runs.str().find(",intermittent,,0.3333333333333333,"), std::string::npos) << "NULL j_paper: " << runs.str();
  EXPECT_EQ(crossings.str(), "job_key,id,t_s,x_m\n0123456789abcdef,3,0.5,-0.001\n0123456789abcdef,0,0.75,0.002\n"
                             "0123456789abcdef,4,2.5,0\n0123456789abcdef,1,2.6,1e-17\n0123456789abcdef,3,2.7,0.001\n");
  EXPECT_THROW(store.export_csv("runs; DROP TABLE runs", runs), std::invalid_argument);
}

TEST(StudyStore, KeepsTheLastStudyFileRunAndReadsStoresWithoutOne) {
  TempDir dir;
  Store store(dir / "runs.sqlite");
  EXPECT_TRUE(store.study_files().empty()) << "a store without the table (as written before it existed)";
  std::ostringstream csv;
  EXPECT_THROW(store.export_csv("study_files", csv), std::invalid_argument);
  store.record_study_file("s", "a/s.toml", "[study]\nname = \"s\"\nreplicates = 3\n");
  store.record_study_file("s", "b/s.toml", "[study]\nname = \"s\"\nreplicates = 5\n");
  const std::vector<StudyFileRecord> files = store.study_files();
  ASSERT_EQ(files.size(), 1u) << "one per study: the last one run";
  EXPECT_EQ(files[0].source, "b/s.toml");
  EXPECT_NE(files[0].text.find("replicates = 5"), std::string::npos);
  EXPECT_FALSE(files[0].recorded_at.empty());
  store.export_csv("study_files", csv);
  EXPECT_EQ(csv.str().rfind("study,source,text,recorded_at\n", 0), 0u) << csv.str();
}

// ------------------------------------------------------------------ runner (no simulation)

TEST(StudyRunner, FailedJobIsReportedAndOthersContinue) {
  TempDir dir;
  const std::vector<Job> jobs = expand_jobs(load_study(tiny_study()));
  Store store(dir / "runs.sqlite");
  RunnerOptions o;
  o.workers = 2;
  std::ostringstream log;
  o.progress = &log;
  const std::string bad = jobs[3].id.key;
  o.run = [&](const Job& job, const std::atomic<bool>*) {
    if (job.id.key == bad) throw std::runtime_error("engine exploded");
    RunRecord r = sample_record();
    r.crossings.clear();
    return r;
  };
  const RunnerSummary s = run_jobs(jobs, store, o);
  EXPECT_EQ(s.total, 12);
  EXPECT_EQ(s.done_now, 11);
  ASSERT_EQ(s.failed.size(), 1u);
  EXPECT_EQ(s.failed[0].id.key, bad);
  EXPECT_FALSE(store.has(bad));
  EXPECT_NE(log.str().find(bad), std::string::npos) << log.str();
  EXPECT_NE(log.str().find("engine exploded"), std::string::npos) << log.str();
  // Running again retries only the failed job.
  o.run = [&](const Job&, const std::atomic<bool>*) { return sample_record(); };
  const RunnerSummary again = run_jobs(jobs, store, o);
  EXPECT_EQ(again.already_stored, 11);
  EXPECT_EQ(again.done_now, 1);
}

TEST(StudyRunner, CancelStopsAndLeavesNoPartialRun) {
  TempDir dir;
  const std::vector<Job> jobs = expand_jobs(load_study(tiny_study()));
  Store store(dir / "runs.sqlite");
  std::atomic<bool> cancel{false};
  std::atomic<int> started{0};
  RunnerOptions o;
  o.workers = 1;
  o.cancel = &cancel;
  o.run = [&](const Job&, const std::atomic<bool>* c) -> RunRecord {
    if (++started == 3) {
      cancel = true;  // as SIGINT would, in the middle of the third run
      if (c && *c) throw RunCancelled();
    }
    return sample_record();
  };
  const RunnerSummary s = run_jobs(jobs, store, o);
  EXPECT_TRUE(s.cancelled);
  EXPECT_EQ(s.done_now, 2);
  EXPECT_TRUE(s.failed.empty()) << "a cancelled run is not a failure";
  EXPECT_EQ(store.count(), 2u);
}

// ------------------------------------------------------------------ runner (tiny simulations)

TEST(StudyRunner, OneAndTwoWorkersStoreIdenticalRecords) {
  TempDir dir;
  const RunnerSummary one = run_tiny(dir / "one.sqlite", 1);
  const RunnerSummary two = run_tiny(dir / "two.sqlite", 2);
  EXPECT_EQ(one.done_now, 12);
  EXPECT_EQ(two.done_now, 12);
  EXPECT_TRUE(one.failed.empty() && two.failed.empty());
  const auto a = dump(dir / "one.sqlite"), b = dump(dir / "two.sqlite");
  EXPECT_EQ(a, b);
  // The tiny study is meant to exercise every table.
  for (const char* table : {"crossings ", "avalanches ", "clogs "})
    EXPECT_TRUE(std::any_of(a.begin(), a.end(), [&](const std::string& r) { return r.rfind(table, 0) == 0; }))
        << "no rows in " << table;
  // Stored records match what the runs report: crossings = passed for every run.
  for (const StoredRun& r : Store(dir / "one.sqlite").load()) {
    EXPECT_EQ(static_cast<int>(r.record.crossings.size()), r.record.passed) << r.id.key;
    EXPECT_EQ(r.record.escaped, 0) << r.id.key;
  }
}

TEST(StudyRunner, ResumeAfterKill9EqualsAnUninterruptedRun) {
  TempDir dir;
  const fs::path killed = dir / "killed.sqlite", log = dir / "log.txt";
  const pid_t pid = spawn_study(killed, log, 1);
  ASSERT_GT(pid, 0);
  const bool some = wait_for_rows(killed, 2, pid);
  kill(pid, SIGKILL);
  wait_exit(pid);
  ASSERT_TRUE(some) << "the child stored no runs; its output:\n" << read_log(log);
  const int after_kill = stored_runs(killed);
  EXPECT_LT(after_kill, 12) << "killed too late to test resuming";

  const pid_t again = spawn_study(killed, log, 2);
  EXPECT_EQ(wait_exit(again), 0) << read_log(log);
  EXPECT_NE(read_log(log).find(fmt::format("{} already stored", after_kill)), std::string::npos) << read_log(log);

  run_tiny(dir / "reference.sqlite", 2);
  const auto resumed = dump(killed), reference = dump(dir / "reference.sqlite");
  EXPECT_EQ(resumed.size(), reference.size());
  EXPECT_TRUE(resumed == reference) << "resumed vs uninterrupted: " << dump_difference(resumed, reference);
  std::set<std::string> keys;
  for (const StoredRun& r : Store(killed).load()) EXPECT_TRUE(keys.insert(r.id.key).second) << r.id.key;
  EXPECT_EQ(keys.size(), 12u);
  // `gapflow study` recorded the study file it ran, for `gapflow report` to read.
  const std::vector<StudyFileRecord> files = Store(killed).study_files();
  ASSERT_EQ(files.size(), 1u);
  EXPECT_EQ(files[0].study, "tiny");
  EXPECT_EQ(files[0].text, *read_text_file(tiny_study()));
}

TEST(StudyRunner, QuickHasItsOwnStore) {
  TempDir dir;
  const fs::path log = dir / "log.txt";
  EXPECT_EQ(wait_exit(spawn_gapflow({"study", tiny_study().string(), "--quick", "--dry-run"}, log)), 0);
  EXPECT_NE(read_log(log).find("store results/tiny-quick/runs.sqlite"), std::string::npos) << read_log(log);
  EXPECT_EQ(wait_exit(spawn_gapflow({"study", tiny_study().string(), "--dry-run"}, log)), 0);
  EXPECT_NE(read_log(log).find("store results/tiny/runs.sqlite"), std::string::npos) << read_log(log);
}

TEST(StudyRunner, QuickWithoutAQuickTableIsAnError) {
  TempDir dir;
  const fs::path study = dir / "no_quick.toml", log = dir / "log.txt";
  std::ofstream(study) << ("[study]\nname = \"nq\"\n[[series]]\nlabel = \"a\"\nscenario = \"" +
                        source_path("scenarios/paper/no_obstruction_medium.toml").string() + "\"\n");
  EXPECT_EQ(wait_exit(spawn_gapflow({"study", study.string(), "--quick", "--dry-run"}, log)), 2);
  const std::string text = read_log(log);
  EXPECT_NE(text.find(study.string()), std::string::npos) << text;
  EXPECT_NE(text.find("no [quick] table"), std::string::npos) << text;
  EXPECT_EQ(wait_exit(spawn_gapflow({"study", study.string(), "--dry-run"}, log)), 0) << read_log(log);
}

TEST(StudyRunner, SigintExits130AndStoresOnlyCompleteRuns) {
  TempDir dir;
  const fs::path db = dir / "runs.sqlite", log = dir / "log.txt";
  const pid_t pid = spawn_study(db, log, 2);
  ASSERT_GT(pid, 0);
  const bool some = wait_for_rows(db, 1, pid);
  kill(pid, SIGINT);
  const int code = wait_exit(pid);
  ASSERT_TRUE(some) << read_log(log);
  if (stored_runs(db) < 12) {  // the signal arrived while runs were in flight
    EXPECT_EQ(code, 130) << read_log(log);
    EXPECT_NE(read_log(log).find("interrupted"), std::string::npos) << read_log(log);
  }
  for (const StoredRun& r : Store(db).load())
    EXPECT_EQ(static_cast<int>(r.record.crossings.size()), r.record.passed) << "complete child rows " << r.id.key;
}

namespace {

// A sweep that gains a value renumbers its points, and runs stored before keep their old index: the
// runs of value 40 stored as point 1 and the new value 35, now point 1, must stay two points in the
// report (it groups by what a run was run at, not by its index).
TEST(StudyStore, ReportKeepsPointsApartWhenASweepWasRenumbered) {
  const auto sweep = [](const std::string& values) {
    return parse(study_text("replicates = 2\nset = [\"particles.count=20\"]",
                            "[[series.sweep]]\nkey = \"bottleneck.gap_mm\"\nvalues = [" + values + "]\n"));
  };
  const std::vector<Job> before = expand_jobs(sweep("30, 40")), after = expand_jobs(sweep("30, 35, 40"));
  std::vector<StoredRun> runs;
  for (const Job& j : before) runs.push_back({j.id, sample_record(), "old", "t"});
  for (const Job& j : after)  // the new value's runs; the others are stored already (same keys)
    if (j.id.point_label == "bottleneck.gap_mm=35") runs.push_back({j.id, sample_record(), "new", "t"});
  ASSERT_EQ(runs[2].id.point, 1);  // value 40, stored under its old index
  ASSERT_EQ(runs[4].id.point, 1);  // value 35, the same index now
  const ReportData d = collect_report_data(runs, {});
  ASSERT_EQ(d.points.size(), 3u);
  for (const ReportPoint& p : d.points) EXPECT_EQ(p.stats.n_runs, 2u) << p.point_label;
  std::set<std::string> labels;
  for (const ReportPoint& p : d.points) labels.insert(p.point_label);
  EXPECT_EQ(labels, (std::set<std::string>{"bottleneck.gap_mm=30", "bottleneck.gap_mm=35", "bottleneck.gap_mm=40"}));
}

}  // namespace

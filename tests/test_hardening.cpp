// Issue 19's reproductions, each through the real command line (build/app/gapflow):
// bad input ends in exit 2 with a message that says what and where, never a crash,
// a hang, exit 1 or a wrong answer with exit 0; files are handled safely.
#include "tests/test_support.hpp"

#include "common/text_file.hpp"
#include "studies/jobs.hpp"
#include "studies/store.hpp"
#include "studies/study.hpp"

#include <gtest/gtest.h>

#include <sys/stat.h>
#include <unistd.h>

#include <fstream>

namespace gapflow {
namespace {

using testing::CliResult;
using testing::run_gapflow;
using testing::shell_quoted;
using testing::source_path;
using testing::TempDir;

const std::string kCylinder = shell_quoted(source_path("scenarios/paper/cylinder.toml").string());

void expect_bad_input(const std::string& args, const std::string& message_part) {
  const CliResult r = run_gapflow(args);
  EXPECT_EQ(r.code, 2) << args << "\n" << r.output;
  EXPECT_NE(r.output.find(message_part), std::string::npos) << args << "\n" << r.output;
}

void write(const std::filesystem::path& p, const std::string& text) { std::ofstream(p) << text; }

// ---------------------------------------------------------------- crash, hangs, memory

TEST(Hardening, TinyPolygonIsRefusedNotABox2DAbort) {
  expect_bad_input("check " + kCylinder +
                       " --set obstruction.shape=polygon --set 'obstruction.vertices_mm=[[0,0],[0.01,0],[0,0.01]]'",
                   "edge 1 is 0.01 mm");
  expect_bad_input("check " + kCylinder + " --set obstruction.shape=polygon --set "
                   "'obstruction.vertices_mm=[[0,0],[10,0],[20,1],[25,5],[26,10],[25,15],[20,19],[10,20],[0,20]]'",
                   "3 to 8");
  expect_bad_input("check " + kCylinder + " --set obstruction.shape=triangle --set obstruction.side_mm=0.001",
                   "obstruction.side_mm");
}

TEST(Hardening, TinyParticlesAndDevicesAndTinyStepsAreBounded) {
  expect_bad_input("check " + kCylinder + " --set particles.diameter_mm=1e-7", "in [0.1, 1000] (mm)");
  expect_bad_input("check " + kCylinder + " --set particles.diameter_mm=1e-320", "particles.diameter_mm");
  expect_bad_input("check /dev/zero", "/dev/zero: is a character device, not a scenario file");
  expect_bad_input("check " + kCylinder + " --set model.box2d.time_step_s=1e-9", "in [1e-05, 0.1] (s)");
  expect_bad_input("check " + kCylinder + " --set model.bullet.time_step_s=1e-9", "in [1e-05, 0.1] (s)");
}

TEST(Hardening, HugeBoardForItsParticlesIsRefusedQuickly) {
  expect_bad_input("check " + kCylinder +
                       " --set plane.width_mm=100000 --set plane.length_mm=100000 --set particles.diameter_mm=0.1 "
                       "--set particles.count=1000000 --set obstruction.shape=none",
                   "lattice sites");
}

TEST(Hardening, StudyJobCountIsCheckedBeforeExpansion) {
  TempDir dir("hardening");
  const std::string scenario = source_path("scenarios/paper/cylinder.toml").string();
  auto study = [&](const std::string& replicates, const std::string& axes) {
    return "[study]\nname = \"big\"\nreplicates = " + replicates + "\n[[series]]\nlabel = \"a\"\nscenario = \"" +
           scenario + "\"\n" + axes;
  };
  write(dir / "a.toml", study("1000000000", ""));
  expect_bad_input("study " + (dir / "a.toml").string() + " --dry-run", "must be an integer in [1, 10000]");
  write(dir / "b.toml", study("2147483648", ""));
  expect_bad_input("study " + (dir / "b.toml").string() + " --dry-run", "'study.replicates' = 2147483648");
  write(dir / "c.toml", study("4294967297", ""));
  expect_bad_input("study " + (dir / "c.toml").string() + " --dry-run", "'study.replicates' = 4294967297");
  const std::string two_axes =
      "[[series.sweep]]\nkey = \"obstruction.distance_mm\"\nfrom = 0\nto = 999\nstep = 1\n"
      "[[series.sweep]]\nkey = \"run.time_limit_s\"\nfrom = 1\nto = 1000\nstep = 1\n";
  write(dir / "d.toml", study("1", two_axes));
  expect_bad_input("study " + (dir / "d.toml").string() + " --dry-run", "expands to 1e+06 jobs");
  const StudyDef parsed = parse_study(study("3", two_axes), "d.toml", dir.path());
  EXPECT_EQ(count_jobs(parsed), 3e6);
}

// ---------------------------------------------------------------- wrong answers with exit 0

TEST(Hardening, NonFiniteSweepsAreRefusedAtTheirKey) {
  TempDir dir("hardening");
  for (const char* bad : {"nan", "inf", "-inf"}) {
    for (const char* key : {"from", "to", "step"}) {
      std::string axis = std::string("[[series.sweep]]\nkey = \"obstruction.distance_mm\"\n") +
                         "from = " + (std::string(key) == "from" ? bad : "0") + "\nto = " +
                         (std::string(key) == "to" ? bad : "10") + "\nstep = " +
                         (std::string(key) == "step" ? bad : "5") + "\n";
      write(dir / "s.toml", "[study]\nname = \"s\"\n[[series]]\nlabel = \"a\"\nscenario = \"" +
                                source_path("scenarios/paper/cylinder.toml").string() + "\"\n" + axis);
      expect_bad_input("study " + (dir / "s.toml").string() + " --dry-run",
                       "'series.sweep." + std::string(key) + "' = " + bad + ": must be a finite number");
    }
  }
}

TEST(Hardening, ObstructionOutsideTheBoardIsRefused) {
  expect_bad_input("check " + kCylinder + " --set obstruction.lateral_offset_mm=400", "outside the board");
  expect_bad_input("check " + kCylinder + " --set obstruction.lateral_offset_mm=-400", "outside the board");
}

TEST(Hardening, ShakingThatFlingsParticlesOffIsRefused) {
  expect_bad_input("check " + kCylinder + " --set shaking.walls.amplitude_mm=1e308", "in [0, 100] (mm)");
}

TEST(Hardening, ARunWhoseParticlesEscapedNeverReadsAsADischarge) {
  RunRecord r;
  r.particles = 50;
  r.escaped = 50;
  EXPECT_TRUE(invalid_run_reason(r));
  std::ostringstream summary;
  write_summary(summary, r);
  EXPECT_NE(summary.str().find("INVALID       50 of 50 particles escaped"), std::string::npos) << summary.str();
  r.escaped = 0;
  EXPECT_FALSE(invalid_run_reason(r));
}

// ---------------------------------------------------------------- exit 1 instead of 2, messages

TEST(Hardening, HugeIntegersInDecimalKeysAreNumbers) {
  expect_bad_input("check " + kCylinder + " --set plane.length_mm=9007199254740993", "in (0, 100000] (mm)");
  const CliResult ok = run_gapflow("check " + kCylinder + " --set obstruction.lateral_offset_mm=-0");
  EXPECT_EQ(ok.code, 0) << ok.output;
}

TEST(Hardening, MessagesBlameTheRightKeyAndSayWhy) {
  expect_bad_input("check " + kCylinder + " --set plane.width_mm=1e308", "'plane.width_mm' = 1e+308");
  expect_bad_input("check " + shell_quoted(source_path("scenarios").string()), "is a directory, not a scenario file");
  expect_bad_input("check /nonexistent/x.toml", "/nonexistent/x.toml: no such file");
  expect_bad_input("study /nonexistent/x.toml", "/nonexistent/x.toml: no such file");
  // The calibration's rule-4 setting: at least one contender (one = the best score is tried).
  const std::string design = shell_quoted(source_path("data/examples/tiny_design.toml").string());
  expect_bad_input("calibrate " + design + " --check --contenders 0", "--contenders: Value 0 not in range 1 to 10");
  EXPECT_EQ(run_gapflow("calibrate " + design + " --check --contenders 1").code, 0);
  // Rule 5's alternatives: 0 (none asked) to 9 (every other catalogue candidate).
  expect_bad_input("calibrate " + design + " --check --alternatives 10", "--alternatives: Value 10 not in range 0 to 9");
  expect_bad_input("calibrate " + design + " --check --alternatives -1", "--alternatives: Value -1 not in range 0 to 9");
  EXPECT_EQ(run_gapflow("calibrate " + design + " --check --alternatives 2").code, 0);
  // The model's replicates in place of the data file's: as the file's own, 2 to 1000.
  expect_bad_input("calibrate " + design + " --check --model-replicates 1", "--model-replicates: Value 1 not in range 2 to 1000");
  const CliResult twelve = run_gapflow("calibrate " + design + " --check --model-replicates 12");
  EXPECT_EQ(twelve.code, 0) << twelve.output;
  EXPECT_NE(twelve.output.find("12 model replicates per point"), std::string::npos) << twelve.output;
}

// ---------------------------------------------------------------- stores

TEST(Hardening, DirectoriesAndDamagedStoresExit2NamingTheFile) {
  TempDir dir("hardening");
  const std::string study = shell_quoted(source_path("studies/examples/tiny.toml").string());
  expect_bad_input("study " + study + " --db " + dir.path().string(), "is a directory");
  write(dir / "text.sqlite", "not a database at all\n");
  expect_bad_input("export " + (dir / "text.sqlite").string(), "text.sqlite is not a SQLite database");
  expect_bad_input("report " + (dir / "text.sqlite").string() + " --no-plots", "text.sqlite is not a SQLite database");
  expect_bad_input("study " + study + " --db " + (dir / "text.sqlite").string(), "is not a SQLite database");
  { Store s(dir / "good.sqlite"); }
  std::filesystem::resize_file(dir / "good.sqlite", 100);  // header intact, pages gone
  expect_bad_input("export " + (dir / "good.sqlite").string(), "good.sqlite");
}

TEST(Hardening, ReadingNeverCreatesAStore) {
  TempDir dir("hardening");
  write(dir / "empty.sqlite", "");
  expect_bad_input("report " + (dir / "empty.sqlite").string() + " --no-plots", "is empty (0 bytes)");
  expect_bad_input("export " + (dir / "empty.sqlite").string(), "is empty (0 bytes)");
  EXPECT_EQ(std::filesystem::file_size(dir / "empty.sqlite"), 0u);
  expect_bad_input("export " + (dir / "absent.sqlite").string(), "no such file");
  EXPECT_FALSE(std::filesystem::exists(dir / "absent.sqlite"));
}

TEST(Hardening, ReadOnlyStoresCanBeExported) {
  TempDir dir("hardening");
  { Store s(dir / "runs.sqlite"); }
  const auto before = std::filesystem::last_write_time(dir / "runs.sqlite");
  ::chmod((dir / "runs.sqlite").c_str(), 0444);
  ::chmod(dir.path().c_str(), 0555);
  // As root permissions do not bind: drop to nobody when we can, so the store really is read-only.
  const std::string as = ::geteuid() == 0 ? "--reuid=65534 --regid=65534 --clear-groups " : "";
  const std::string cmd = as.empty() ? "" : "setpriv " + as;
  const std::string out = "timeout 30 " + cmd + GAPFLOW_BINARY_DIR "/app/gapflow export " +
                          (dir / "runs.sqlite").string() + " --table runs 2>&1";
  FILE* p = popen(out.c_str(), "r");
  ASSERT_TRUE(p);
  std::string text;
  char buf[512];
  for (std::size_t n; (n = fread(buf, 1, sizeof buf, p)) > 0;) text.append(buf, n);
  const int status = pclose(p);
  ::chmod(dir.path().c_str(), 0755);
  EXPECT_EQ(WEXITSTATUS(status), 0) << text;
  EXPECT_EQ(text.rfind("job_key,study,", 0), 0u) << text;
  EXPECT_EQ(std::filesystem::last_write_time(dir / "runs.sqlite"), before);
}

TEST(Hardening, ASecondStudyOnTheSameStoreRefusesAtStart) {
  TempDir dir("hardening");
  const Store first(dir / "runs.sqlite", StoreAccess::exclusive);
  EXPECT_THROW(Store(dir / "runs.sqlite", StoreAccess::exclusive), StoreError);
  expect_bad_input("study " + shell_quoted(source_path("studies/examples/tiny.toml").string()) + " --db " +
                       (dir / "runs.sqlite").string(),
                   "is being written by another gapflow study (process " + std::to_string(::getpid()) + ")");
  EXPECT_EQ(first.count(), 0u);
}

TEST(Hardening, TheWriterLockIsReleasedOnClose) {
  TempDir dir("hardening");
  { Store a(dir / "runs.sqlite", StoreAccess::exclusive); }
  EXPECT_FALSE(std::filesystem::exists(dir / "runs.sqlite.lock"));
  EXPECT_NO_THROW(Store(dir / "runs.sqlite", StoreAccess::exclusive));
}

// ---------------------------------------------------------------- file safety

TEST(Hardening, ExportRefusesNonRegularTargetsAndLeavesNoPartialFile) {
  TempDir dir("hardening");
  { Store s(dir / "runs.sqlite"); }
  const std::string db = (dir / "runs.sqlite").string();
  ASSERT_EQ(::mkfifo((dir / "fifo").c_str(), 0644), 0);
  expect_bad_input("export " + db + " --csv " + (dir / "fifo").string(), "is a FIFO (named pipe)");
  expect_bad_input("export " + db + " --csv /dev/null", "is a character device");
  expect_bad_input("export " + db + " --csv " + dir.path().string(), "is a directory");
  expect_bad_input("export " + db + " --csv " + (dir / "no/such/folder.csv").string(), "does not exist");
  EXPECT_FALSE(std::filesystem::exists(dir / "fifo.partial"));
  struct stat st {};
  ASSERT_EQ(::stat((dir / "fifo").c_str(), &st), 0);
  EXPECT_TRUE(S_ISFIFO(st.st_mode));
  const CliResult ok = run_gapflow("export " + db + " --csv " + (dir / "runs.csv").string());
  EXPECT_EQ(ok.code, 0) << ok.output;
  EXPECT_TRUE(std::filesystem::exists(dir / "runs.csv"));
  EXPECT_FALSE(std::filesystem::exists(dir / "runs.csv.partial"));
}

// The views' outputs (--movie, --vtk, --snapshot-dir) and calibrate --out are checked before the run like --out:
// a device or FIFO is never replaced by a movie (as root, --movie /dev/null once did), and
// a file named as a folder is neither written into nor replaced.
TEST(Hardening, OutputTargetsThatAreNotOursAreRefusedBeforeTheWork) {
  TempDir dir("hardening_views");
  const std::filesystem::path fifo = dir / "pipe", file = dir / "notes.txt", folder = dir / "folder";
  ASSERT_EQ(mkfifo(fifo.c_str(), 0600), 0);
  write(file, "the user's notes");
  std::filesystem::create_directories(folder);
  const std::string run = "run " + kCylinder + " --set particles.count=20 --set run.time_limit_s=0.2 --quiet ";
  expect_bad_input(run + "--movie " + shell_quoted(fifo.string()), "is a");
  expect_bad_input(run + "--movie " + shell_quoted(folder.string()), "is a directory");
  expect_bad_input(run + "--vtk " + shell_quoted(file.string()), "is not a folder");
  expect_bad_input(run + "--snapshot-at 0 --snapshot-dir " + shell_quoted(file.string()), "is not a folder");
  // The same rule for the folders of a calibration and a report, checked before the work.
  const std::string design = shell_quoted(source_path("data/examples/tiny_design.toml").string());
  expect_bad_input("calibrate " + design + " --no-plots --out " + shell_quoted(file.string()), "is not a folder");
  struct stat st {};
  ASSERT_EQ(lstat(fifo.c_str(), &st), 0);
  EXPECT_TRUE(S_ISFIFO(st.st_mode)) << "the FIFO was replaced";
  EXPECT_EQ(read_text_file(file).value_or(""), "the user's notes");
  EXPECT_FALSE(std::filesystem::exists(dir / "folder.partial"));
}

TEST(Hardening, AFailedWriteRemovesThePartialFile) {
  TempDir dir("hardening");
  EXPECT_THROW(write_file_atomically(dir / "x.csv", [](std::ostream&) { throw std::runtime_error("boom"); }),
               std::runtime_error);
  EXPECT_FALSE(std::filesystem::exists(dir / "x.csv.partial"));
  EXPECT_FALSE(std::filesystem::exists(dir / "x.csv"));
}

TEST(Hardening, RunChecksItsOutputPathBeforeSimulating) {
  const CliResult r = run_gapflow("run " + kCylinder + " --out /nonexistent/record.json", 10);
  EXPECT_EQ(r.code, 2) << r.output;
  EXPECT_NE(r.output.find("/nonexistent/record.json: the folder /nonexistent does not exist"), std::string::npos)
      << r.output;
  EXPECT_EQ(r.output.find("running"), std::string::npos) << "refused before the simulation: " << r.output;
}

TEST(Hardening, LostStandardOutputIsAFailure) {
  // stderr goes to the pipe (2>&3), stdout to the full device.
  const CliResult r = run_gapflow("check " + kCylinder + " --print 3>&1 2>&3 >/dev/full");
  EXPECT_EQ(r.code, 1) << r.output;
}

}  // namespace
}  // namespace gapflow

// Seeded mutation fuzzer over the shipped scenario, study and measured-data files, through the real
// command line: every mutant must end in exit 0 or 2 within the time bound, never a
// signal (crash, abort), exit 1 or a hang (killed by `timeout`, 137).
//
//   default (CI):  kDefaultCases cases, seed 1, ~10 s on one core
//   on demand:     GAPFLOW_FUZZ_CASES=5000 GAPFLOW_FUZZ_SEED=7 build/tests/gapflow_tests --gtest_filter='Fuzz*'
//
// A failing mutant is written to tests/fuzz_corpus/found_<seed>_<case>.toml (the message
// says so): fix the bug, rename the file (scenario_*.toml, study_*.toml or data_*.toml) and keep it;
// the regression corpus is replayed by FuzzCorpus.* on every test run.
#include "tests/test_support.hpp"

#include "common/random.hpp"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <algorithm>

#include <chrono>
#include <cstdlib>
#include <fstream>
#include <regex>
#include <sstream>

namespace gapflow {
namespace {

namespace fs = std::filesystem;
using testing::CliResult;
using testing::run_gapflow;
using testing::shell_quoted;
using testing::source_path;
using testing::TempDir;

constexpr int kDefaultCases = 120;
constexpr int kTimeBoundS = 20;  // far above any check or --dry-run of a shipped file (< 0.3 s)

int env_int(const char* name, int fallback) {
  const char* v = std::getenv(name);
  return v && *v ? std::atoi(v) : fallback;
}

std::string read_all(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

std::vector<fs::path> files_in(const std::string& folder) {
  std::vector<fs::path> out;
  for (const auto& e : fs::recursive_directory_iterator(source_path(folder)))
    if (e.path().extension() == ".toml") out.push_back(e.path());
  std::sort(out.begin(), out.end());
  return out;
}

// Values that have broken loaders before: limits of int32/int64/double, non-finite,
// denormal, wrong types, paths that are not files.
const std::vector<std::string> kInteresting{
    "0", "-0", "-1", "1", "1e-320", "1e-7", "1e308", "-1e308", "nan", "inf", "-inf", "2147483648", "4294967297",
    "9007199254740993", "9223372036854775807", "-9223372036854775808", "1e-9", "0.0001", "100000", "100001",
    "\"\"", "\"x\"", "\"/dev/zero\"", "\".\"", "true", "[]", "[[0, 0], [0.01, 0], [0, 0.01]]", "{}", "1979-05-27"};

// Scenario keys to override with --set (a mix of every section's).
const std::vector<std::string> kKeys{
    "plane.incline_deg", "plane.length_mm", "plane.width_mm", "bottleneck.wall_angle_deg", "bottleneck.gap_mm",
    "bottleneck.wall_thickness_mm", "particles.count", "particles.diameter_mm", "particles.size_scatter",
    "particles.density_kg_m3", "release.barrier_mm", "release.settle_s", "release.lattice_gap", "obstruction.shape",
    "obstruction.diameter_mm", "obstruction.side_mm", "obstruction.vertices_mm", "obstruction.distance_mm",
    "obstruction.lateral_offset_mm", "shaking.walls.amplitude_mm", "shaking.walls.frequency_hz",
    "shaking.walls.decay_s", "protocol.perturb_radius_d", "run.end", "run.time_limit_s", "run.n_passed",
    "run.clog_timeout_s", "run.stranded_max", "run.seed", "model.box2d.time_step_s", "model.box2d.engine_diameter",
    "model.bullet.time_step_s", "no.such_key", "plane"};

class Mutator {
 public:
  explicit Mutator(std::uint64_t seed) : rng_(splitmix64(seed)) {}

  std::size_t below(std::size_t n) { return n ? static_cast<std::size_t>(rng_.next_u64() % n) : 0; }
  template <class T>
  const T& pick(const std::vector<T>& v) { return v[below(v.size())]; }

  std::string mutate(std::string text) {
    const int rounds = 1 + static_cast<int>(below(3));
    for (int i = 0; i < rounds; ++i) text = once(std::move(text));
    return text;
  }

  // "key=value" overrides for a scenario mutant.
  std::vector<std::string> overrides() {
    std::vector<std::string> out;
    for (std::size_t n = below(3); n-- > 0;) out.push_back(pick(kKeys) + "=" + pick(kInteresting));
    return out;
  }

 private:
  std::string once(std::string text) {
    std::vector<std::string> lines;
    {
      std::istringstream in(text);
      for (std::string line; std::getline(in, line);) lines.push_back(line);
    }
    if (lines.empty()) lines.push_back("");
    const std::size_t k = below(lines.size());
    switch (below(8)) {
      case 0: case 1: case 2: {  // a value replaced by an interesting one (most productive)
        static const std::regex value(R"((=\s*)([^#\n]+))");
        lines[k] = std::regex_replace(lines[k], value, "$1" + pick(kInteresting), std::regex_constants::format_first_only);
        break;
      }
      case 3: lines.erase(lines.begin() + static_cast<long>(k)); break;
      case 4: lines.insert(lines.begin() + static_cast<long>(below(lines.size())), lines[k]); break;
      case 5: std::swap(lines[k], lines[below(lines.size())]); break;
      case 6: {  // a byte flipped, inserted or the text cut
        std::string& l = lines[k];
        const std::size_t at = below(l.size() + 1);
        const char byte = static_cast<char>(below(256));
        if (below(2) && at < l.size()) l[at] = byte;
        else l.insert(at, 1, byte);
        break;
      }
      default: {  // a number scaled by a power of ten
        static const std::regex number(R"(([-+]?[0-9]+(\.[0-9]+)?))");
        std::smatch m;
        if (std::regex_search(lines[k], m, number))
          lines[k].replace(static_cast<std::size_t>(m.position(0)), static_cast<std::size_t>(m.length(0)),
                           m.str(0) + "e" + std::to_string(static_cast<int>(below(41)) - 20));
      }
    }
    std::string out;
    for (const std::string& l : lines) out += l + "\n";
    return out;
  }

  RandomStream rng_;
};

// Study files name their scenarios relative to themselves; mutants live elsewhere.
std::string absolute_scenarios(std::string text) {
  return std::regex_replace(text, std::regex(R"(\.\./\.\./scenarios/)"), source_path("scenarios").string() + "/");
}

// A data file's scenario and CSV are relative to it; the mutant lives elsewhere.
std::string absolute_data_paths(std::string text, const fs::path& base) {
  const std::string dir = base.parent_path().string() + "/";
  text = std::regex_replace(text, std::regex(R"((scenario\s*=\s*")([^"/][^"]*"))"), "$1" + dir + "$2");
  return std::regex_replace(text, std::regex(R"((csv\s*=\s*")([^"/][^"]*"))"), "$1" + dir + "$2");
}

bool acceptable(int code) { return code == 0 || code == 2; }

std::string describe(const CliResult& r) {
  if (r.code == 137 || r.code == 124) return "a hang (killed after " + std::to_string(kTimeBoundS) + " s)";
  if (r.code > 128) return "signal " + std::to_string(r.code - 128);
  return "exit " + std::to_string(r.code);
}

TEST(Fuzz, MutatedScenarioAndStudyFilesExitZeroOrTwo) {
  const int cases = env_int("GAPFLOW_FUZZ_CASES", kDefaultCases);
  const std::uint64_t seed = static_cast<std::uint64_t>(env_int("GAPFLOW_FUZZ_SEED", 1));
  const std::vector<fs::path> scenarios = files_in("scenarios"), studies = files_in("studies"), data_files = files_in("data");
  ASSERT_FALSE(scenarios.empty());
  ASSERT_FALSE(data_files.empty());
  ASSERT_FALSE(studies.empty());
  TempDir dir("fuzz");
  Mutator m(seed);
  int failures = 0, by_code[3] = {0, 0, 0};
  const auto start = std::chrono::steady_clock::now();
  for (int i = 0; i < cases; ++i) {
    const int kind = m.below(6);  // 0-1 study, 2 measured-data file, 3-5 scenario
    const bool study = kind < 2, data = kind == 2;
    const fs::path& base = study ? m.pick(studies) : data ? m.pick(data_files) : m.pick(scenarios);
    std::string text = read_all(base);
    if (study) text = absolute_scenarios(text);
    if (data) text = absolute_data_paths(text, base);
    const std::string mutant = m.mutate(text);
    const fs::path file = dir / (std::to_string(i) + ".toml");
    std::ofstream(file, std::ios::binary) << mutant;
    std::string args;
    if (study) {
      args = "study " + shell_quoted(file.string()) + " --dry-run --db " + shell_quoted((dir / "none.sqlite").string());
    } else if (data) {
      args = "calibrate " + shell_quoted(file.string()) + " --check";
    } else {
      args = "check " + shell_quoted(file.string());
      for (const std::string& o : m.overrides()) args += " --set " + shell_quoted(o);
    }
    const CliResult r = run_gapflow(args, kTimeBoundS);
    if (acceptable(r.code)) {
      ++by_code[r.code];
      continue;
    }
    ++failures;
    const fs::path keep = source_path("tests/fuzz_corpus") /
                          fmt::format("found_{}_{}_{}.toml", study ? "study" : data ? "data" : "scenario", seed, i);
    std::ofstream(keep, std::ios::binary) << mutant;
    ADD_FAILURE() << "case " << i << " (seed " << seed << ", from " << base.filename().string() << "): "
                  << describe(r) << "\n  gapflow " << args << "\n  mutant kept as " << keep.string() << "\n"
                  << r.output.substr(0, 2000);
  }
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::cout << fmt::format("fuzz: {} cases (seed {}) in {:.1f} s: {} exit 0, {} exit 2, {} failures\n", cases, seed,
                           seconds, by_code[0], by_code[2], failures);
  EXPECT_GT(by_code[2], 0) << "no mutant was rejected: the mutator is not reaching the loaders";
}

// The regression corpus: inputs that once crashed, hung or answered wrongly.
TEST(FuzzCorpus, EveryKeptInputEndsInExitTwo) {
  int n = 0;
  for (const auto& e : fs::directory_iterator(source_path("tests/fuzz_corpus"))) {
    const fs::path& p = e.path();
    if (p.extension() != ".toml") continue;
    const std::string name = p.filename().string();
    const bool study = name.rfind("study_", 0) == 0 || name.find("_study_") != std::string::npos;
    const bool data = name.rfind("data_", 0) == 0 || name.find("_data_") != std::string::npos;
    const std::string args = study ? "study " + shell_quoted(p.string()) + " --dry-run --db /nonexistent/x"
                             : data ? "calibrate " + shell_quoted(p.string()) + " --check"
                                    : "check " + shell_quoted(p.string());
    const CliResult r = run_gapflow(args, kTimeBoundS);
    EXPECT_EQ(r.code, 2) << name << ": " << describe(r) << "\n" << r.output;
    ++n;
  }
  EXPECT_GE(n, 8);
}

}  // namespace
}  // namespace gapflow

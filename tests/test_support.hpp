// Helpers shared by the tests: scenario loading from text or from scenarios/.
#pragma once

#include "models/registry.hpp"
#include "common/geometry.hpp"
#include "common/scenario_loader.hpp"

#include <filesystem>
#include <string>
#include <vector>

namespace gapflow::testing {

// Path of a file in the source tree, e.g. source_path("scenarios/paper/no_obstruction_medium.toml").
std::filesystem::path source_path(const std::string& relative);

// Parse and compile a scenario given as TOML text (throws on error).
CompiledScenario compile_text(const std::string& toml, const std::vector<std::string>& overrides = {});
// A board far larger than the particles (3000 x 600 mm, gap 300 mm, barrier at 1500 mm, no
// settling, equal medium spheres), for tests that place particles by hand.
std::string open_board_scenario(const std::string& name, int count, double incline_deg = 8.0);
// The head of a calibration data file for loader tests: [data] to one [[design]] column
// (W_over_d in d, on the paper's medium template); `model_lines` are the [model] lines after
// its scenario. 14 lines plus model_lines (the text starts with an empty line).
std::string data_file_head(const std::string& model_lines);
// Load and compile a shipped scenario file.
CompiledScenario compile_file(const std::string& relative, const std::vector<std::string>& overrides = {});

// A fresh folder per test, removed afterwards (ctest runs tests in parallel processes).
class TempDir {
 public:
  explicit TempDir(const std::string& prefix);
  ~TempDir();
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  std::filesystem::path operator/(const std::string& name) const { return path_ / name; }
  const std::filesystem::path& path() const { return path_; }

 private:
  std::filesystem::path path_;
};

// One run of the gapflow command line (build/app/gapflow) under `timeout`.
struct CliResult {
  int code = -1;       // exit code; 124 = timed out, 128 + n = killed by signal n
  std::string output;  // standard output and standard error, interleaved
};
// args are passed to the shell as written (quote what needs quoting).
CliResult run_gapflow(const std::string& args, int timeout_s = 30);
// Single-quoted for the shell.
std::string shell_quoted(const std::string& s);

}  // namespace gapflow::testing

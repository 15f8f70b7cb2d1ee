#include "tests/test_support.hpp"

#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>

namespace gapflow::testing {

std::string data_file_head(const std::string& model_lines) {
  return "\n[data]\nname = \"t\"\n[source]\ncitation = \"test\"\nmethod = \"simulated\"\nuncertainty = \"se of 10 runs\"\n"
         "[model]\nscenario = \"scenarios/paper/no_obstruction_medium.toml\"\n" +
         model_lines + "[observable]\nkind = \"j_mid\"\n[[design]]\ncolumn = \"W_over_d\"\nkey = \"bottleneck.gap_mm\"\nunit = \"d\"\n";
}

std::filesystem::path source_path(const std::string& relative) {
  return std::filesystem::path(GAPFLOW_SOURCE_DIR) / relative;
}

std::string open_board_scenario(const std::string& name, int count, double incline_deg) {
  return "[scenario]\nname = \"" + name + "\"\n[plane]\nincline_deg = " + std::to_string(incline_deg) +
         "\nlength_mm = 3000.0\nwidth_mm = 600.0\n[bottleneck]\ngap_mm = 300.0\n[particles]\ncount = " +
         std::to_string(count) +
         "\ndiameter_mm = \"medium\"\nsize_scatter = 0.0\n[release]\nbarrier_mm = 1500.0\nsettle_s = 0.0\n";
}

CompiledScenario compile_text(const std::string& toml, const std::vector<std::string>& overrides) {
  LoadedScenario loaded = parse_scenario(toml, "test.toml", overrides);
  try {
    return compile_scenario(loaded.def);
  } catch (const ScenarioInvalid& e) {
    throw locate(e, loaded);
  }
}

CompiledScenario compile_file(const std::string& relative, const std::vector<std::string>& overrides) {
  LoadedScenario loaded = load_scenario(source_path(relative), overrides);
  try {
    return compile_scenario(loaded.def);
  } catch (const ScenarioInvalid& e) {
    throw locate(e, loaded);
  }
}

TempDir::TempDir(const std::string& prefix) {
  const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
  path_ = std::filesystem::temp_directory_path() /
          (prefix + "-" + std::to_string(getpid()) + "-" + (info ? info->name() : "x"));
  std::filesystem::remove_all(path_);
  std::filesystem::create_directories(path_);
}

TempDir::~TempDir() { std::filesystem::remove_all(path_); }

std::string shell_quoted(const std::string& s) {
  std::string q = "'";
  for (char c : s) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return q + "'";
}

CliResult run_gapflow(const std::string& args, int timeout_s) {
  const std::string cmd = "timeout -s KILL " + std::to_string(timeout_s) + " " GAPFLOW_BINARY_DIR "/app/gapflow " +
                          args + " 2>&1";
  CliResult r;
  FILE* p = popen(cmd.c_str(), "r");
  if (!p) return r;
  char buf[4096];
  for (std::size_t n; (n = fread(buf, 1, sizeof buf, p)) > 0;) r.output.append(buf, n);
  const int status = pclose(p);
  r.code = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  return r;
}

}  // namespace gapflow::testing

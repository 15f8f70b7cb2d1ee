#include "tests/test_support.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

namespace gapflow::testing {

std::filesystem::path source_path(const std::string& relative) {
  return std::filesystem::path(GAPFLOW_SOURCE_DIR) / relative;
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

}  // namespace gapflow::testing

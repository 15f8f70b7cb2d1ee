#include "tests/test_support.hpp"

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

}  // namespace gapflow::testing

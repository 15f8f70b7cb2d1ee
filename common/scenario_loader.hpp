// Strict TOML loader for ScenarioDef (toml++).
//
// Parse and validate once (MuJoCo style): unknown keys, wrong types and values
// outside their allowed range are errors that say file:line:column, the key, the
// bad value and what is allowed. Cross-field checks that need geometry (gap wider
// than the channel, obstruction overlapping a wall, plane too short for the
// packing) are done by compile_scenario() and reported through the same
// ScenarioError, located with the SourceMap kept here.
#pragma once

#include "common/scenario.hpp"

#include <cstdint>
#include <filesystem>
#include <map>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

namespace gapflow {

struct SourceLocation {
  std::string source;  // file path, or "--set" for a command-line override
  int line = 0;        // 1-based; 0 = unknown
  int column = 0;      // 1-based; 0 = unknown
};

// Where each key (dotted, e.g. "obstruction.distance_mm") was set.
using SourceMap = std::map<std::string, SourceLocation>;

// A scenario that cannot be used. what() is the complete one-line message:
//   file:line:column: key 'obstruction.distance_mm' = -3: must be >= 0 (...)
class ScenarioError : public std::runtime_error {
 public:
  ScenarioError(SourceLocation where, std::string key, std::string value, std::string allowed);
  const SourceLocation& where() const { return where_; }
  const std::string& key() const { return key_; }
  const std::string& value() const { return value_; }
  const std::string& allowed() const { return allowed_; }

 private:
  SourceLocation where_;
  std::string key_, value_, allowed_;
};

// A check that failed on a complete ScenarioDef (no location known yet).
// Thrown by compile_scenario(); locate() turns it into a ScenarioError.
class ScenarioInvalid : public std::runtime_error {
 public:
  ScenarioInvalid(std::string key, std::string value, std::string allowed);
  std::string key, value, allowed;
};

struct LoadedScenario {
  ScenarioDef def;
  SourceMap where;
  std::string source;  // path of the file
};

// Load a file and apply "key=value" overrides (each validated like the file).
LoadedScenario load_scenario(const std::filesystem::path& file,
                             const std::vector<std::string>& overrides = {});
// Same, from text (tests). source_name is what error messages call the file.
LoadedScenario parse_scenario(std::string_view text, std::string_view source_name,
                              const std::vector<std::string>& overrides = {});

// Attach the location of e.key (or of its section) to a ScenarioInvalid.
ScenarioError locate(const ScenarioInvalid& e, const LoadedScenario& s);

// Canonical, complete TOML text of a scenario (every key, fixed order and format).
std::string canonical_toml(const ScenarioDef& def);
// Stable 64-bit hash of canonical_toml (identifies a resolved scenario).
std::uint64_t scenario_hash(const ScenarioDef& def);

}  // namespace gapflow

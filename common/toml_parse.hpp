// Parse TOML text; a syntax error becomes a ScenarioError at its file:line:column.
// Shared by the scenario, study and report loaders.
#pragma once

#include "common/scenario_loader.hpp"

#include <algorithm>
#include <string>
#include <string_view>
#include <toml++/toml.h>

namespace gapflow {

inline toml::table parse_toml_located(std::string_view text, const std::string& source) {
  try {
    return toml::parse(text, source);
  } catch (const toml::parse_error& e) {
    const auto& p = e.source().begin;
    throw ScenarioError({source, static_cast<int>(std::max(1u, p.line)), static_cast<int>(std::max(1u, p.column))},
                        "", "", std::string(e.description()));
  }
}

}  // namespace gapflow

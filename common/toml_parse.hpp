// Parse TOML text; a syntax error becomes a ScenarioError at its file:line:column.
// Shared by the scenario, study and report loaders.
#pragma once

#include "common/scenario_loader.hpp"

#include <algorithm>
#include <optional>
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

// A number node as a double; integers of any size too (toml++'s value<double>() gives
// nothing for an integer beyond +-2^53, which is still a perfectly good number here).
inline std::optional<double> number_value(const toml::node& n) {
  if (auto i = n.as_integer()) return static_cast<double>(i->get());
  if (auto f = n.as_floating_point()) return f->get();
  return std::nullopt;
}

}  // namespace gapflow

// How a value is spelled in TOML: shared by the scenario loader's messages and
// the canonical scenario text that scenario_hash reads (so a change here changes
// every stored run's scenario hash; the hash tests in test_effects.cpp pin it).
#pragma once

#include <string>
#include <string_view>

namespace gapflow {

// Shortest text that reads back to the same double, spelled as a TOML float
// (a bare "1000" would read back as an integer); nan and inf as TOML spells them.
std::string toml_double(double v);

// A TOML basic string: quotes, backslashes and control characters escaped.
std::string toml_quote(std::string_view s);

// A key as TOML spells it: bare when it is only A-Z a-z 0-9 _ -, else quoted.
std::string toml_key(std::string_view s);

}  // namespace gapflow

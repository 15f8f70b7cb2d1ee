// The [screen] table's strict loader (keys and units: studies/screen_def.hpp).
#pragma once

#include "common/toml_strict.hpp"
#include "studies/study.hpp"

namespace gapflow {

// Read [screen] (root: the whole study file, to refuse [[series]] and [confirm] beside it) and
// fill study.screen and study.series. Errors are ScenarioErrors at file:line:column.
void read_screen(const toml::table& root, const toml::table& screen, const std::string& source,
                 const std::filesystem::path& base_dir, StudyDef& study);

}  // namespace gapflow

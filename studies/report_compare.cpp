// `gapflow report --compare`: do the two study files run their common series alike?
// The other model's runs join the report as if run here, which is only a comparison of
// models if the two studies fixed the same settings: the [study] overrides, and for every
// series both have, its scenario file and overrides. [per_model] sets are one model's by
// design (e.g. the 2D rolling contact) and are not compared.
#include "studies/report.hpp"

#include "common/toml_parse.hpp"

#include <fmt/format.h>

#include <filesystem>
#include <map>
#include <string>
#include <vector>

namespace gapflow {

namespace {

// key -> value of a `set = ["key=value", ...]` array (absent: empty).
std::map<std::string, std::string> overrides(const toml::node_view<const toml::node>& set) {
  std::map<std::string, std::string> out;
  if (const toml::array* a = set.as_array())
    for (const toml::node& n : *a)
      if (auto s = n.value<std::string>()) {
        const std::size_t eq = s->find('=');
        out[s->substr(0, eq)] = eq == std::string::npos ? "" : s->substr(eq + 1);
      }
  return out;
}

struct SeriesSettings {
  std::string scenario;  // file name (the two files may sit in different folders)
  std::map<std::string, std::string> set;
};

std::map<std::string, SeriesSettings> series_settings(const toml::table& doc) {
  std::map<std::string, SeriesSettings> out;
  if (const toml::array* series = doc["series"].as_array())
    for (const toml::node& n : *series)
      if (const toml::table* t = n.as_table())
        if (auto label = (*t)["label"].value<std::string>()) {
          SeriesSettings s;
          s.scenario = std::filesystem::path((*t)["scenario"].value_or(std::string{})).filename().string();
          s.set = overrides(toml::node_view<const toml::node>(t->get("set")));
          out[*label] = s;
        }
  return out;
}

// "k: a vs b" for every key whose value differs (or is set in one only).
void differing(const std::map<std::string, std::string>& a, const std::map<std::string, std::string>& b,
               const std::string& where, std::vector<std::string>& out) {
  std::map<std::string, std::pair<std::string, std::string>> all;
  for (const auto& [k, v] : a) all[k].first = v;
  for (const auto& [k, v] : b) all[k].second = v;
  for (const auto& [k, v] : all)
    if (v.first != v.second)
      out.push_back(fmt::format("{} {}: {} here, {} there", where, k, v.first.empty() ? "unset" : v.first,
                                v.second.empty() ? "unset" : v.second));
}

}  // namespace

std::vector<std::string> study_setting_differences(std::string_view own_text, const std::string& own_source,
                                                   std::string_view other_text, const std::string& other_source) {
  const toml::table own = parse_toml_located(own_text, own_source);
  const toml::table other = parse_toml_located(other_text, other_source);
  std::vector<std::string> out;
  differing(overrides(own["study"]["set"]), overrides(other["study"]["set"]), "[study] set", out);
  const auto a = series_settings(own), b = series_settings(other);
  for (const auto& [label, s] : a) {
    const auto it = b.find(label);
    if (it == b.end()) continue;
    if (s.scenario != it->second.scenario)
      out.push_back(fmt::format("series '{}' scenario: {} here, {} there", label, s.scenario, it->second.scenario));
    differing(s.set, it->second.set, fmt::format("series '{}' set", label), out);
  }
  return out;
}

}  // namespace gapflow

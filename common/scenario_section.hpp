// The scenario loader's strict section reader (internal to scenario_loader.cpp):
// a Section hands out its table's keys with their types and ranges checked, and
// records every key it was asked for, so that finish() can reject the rest as
// unknown keys and list what is allowed. Reader records where each key was set
// (file:line:column, or the --set override that wrote it).
#pragma once

#include "common/input_bounds.hpp"
#include "common/scenario_loader.hpp"
#include "common/toml_parse.hpp"
#include "common/toml_spelling.hpp"

#include <fmt/format.h>
#include <toml++/toml.h>

#include <algorithm>
#include <initializer_list>
#include <cmath>
#include <cstdint>
#include <limits>
#include <map>
#include <optional>
#include <sstream>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace gapflow::scenario_reading {

// The value as TOML would spell it, for error messages.
inline std::string value_text(const toml::node& n) {
  if (auto s = n.as_string()) return toml_quote(s->get());
  if (auto i = n.as_integer()) return std::to_string(i->get());
  if (auto f = n.as_floating_point()) return toml_double(f->get());
  if (auto b = n.as_boolean()) return b->get() ? "true" : "false";
  if (auto a = n.as_array()) {
    std::string out = "[";
    for (std::size_t k = 0; k < a->size(); ++k) out += (k ? ", " : "") + value_text(*a->get(k));
    return out + "]";
  }
  if (n.is_table()) return "{...}";
  std::ostringstream os;  // dates and times
  n.visit([&](auto&& v) { os << v; });
  return os.str();
}

// ---------------------------------------------------------------- reader

struct Reader {
  std::string source;
  std::map<std::string, SourceLocation> overridden;  // keys (and tables) written by --set
  SourceMap where;

  SourceLocation locate(const std::string& key, const toml::node& n) const {
    if (auto it = overridden.find(key); it != overridden.end()) return it->second;
    const auto& begin = n.source().begin;
    if (begin.line == 0) return {source, 1, 1};
    return {source, static_cast<int>(begin.line), static_cast<int>(begin.column)};
  }
};

inline std::string join_dotted(const std::string& path, std::string_view key) {
  return path.empty() ? std::string(key) : path + "." + std::string(key);
}

// One table of the scenario. Every accessor registers its key as allowed.
class Section {
 public:
  Section(Reader& r, const toml::table* t, std::string path) : r_(r), t_(t), path_(std::move(path)) {}

  const std::string& path() const { return path_; }
  bool present() const { return t_ != nullptr; }
  std::string dotted(std::string_view key) const { return join_dotted(path_, key); }

  // The node of `key`, or nullptr. Records where it was set.
  const toml::node* get(std::string_view key) {
    allowed_.emplace_back(key);
    const toml::node* n = t_ ? t_->get(key) : nullptr;
    if (n) r_.where[dotted(key)] = r_.locate(dotted(key), *n);
    return n;
  }
  // A key that is allowed but not used (shape-specific keys of another shape).
  void ignore(std::string_view key) { get(key); }

  bool set(std::string_view key) const { return r_.where.count(dotted(key)) > 0; }
  // Where this section starts; the top of the file for the root or an absent section.
  SourceLocation section_location() const {
    if (auto it = r_.where.find(path_); !path_.empty() && it != r_.where.end()) return it->second;
    return {r_.source, 1, 1};
  }
  // Where `key` was set; else where its section starts.
  SourceLocation location(std::string_view key) const {
    if (auto it = r_.where.find(dotted(key)); it != r_.where.end()) return it->second;
    return section_location();
  }

  [[noreturn]] void fail(std::string_view key, const toml::node& n, const std::string& allowed) const {
    throw ScenarioError(r_.locate(dotted(key), n), dotted(key), value_text(n), allowed);
  }
  // A check between keys: blame `key`, shown with `value` (its current value).
  [[noreturn]] void fail_value(std::string_view key, const std::string& value, const std::string& allowed,
                               std::string_view fallback_key = {}) const {
    bool given = set(key);
    SourceLocation at = given || fallback_key.empty() ? location(key) : location(fallback_key);
    throw ScenarioError(at, dotted(key), given ? value : value + " (default)", allowed);
  }
  [[noreturn]] void missing(std::string_view key, const std::string& allowed,
                            std::optional<SourceLocation> at = std::nullopt) const {
    throw ScenarioError(at ? *at : section_location(), dotted(key), "", allowed);
  }

  Section section(std::string_view key) {
    const toml::node* n = get(key);
    if (n && !n->is_table()) fail(key, *n, fmt::format("must be a table (section [{}])", dotted(key)));
    return Section(r_, n ? n->as_table() : nullptr, dotted(key));
  }

  std::optional<double> number(std::string_view key, const Range& range) {
    const toml::node* n = get(key);
    if (!n) return std::nullopt;
    std::string bounds = range.text();
    std::string sep = bounds.empty() ? "" : " ";
    if (!n->is_number()) fail(key, *n, "must be a number" + sep + bounds);
    const double v = *number_value(*n);
    if (!std::isfinite(v)) fail(key, *n, "must be a finite number" + sep + bounds);
    if (!range.contains(v)) fail(key, *n, "must be " + bounds);
    return v;
  }
  void number(std::string_view key, double& out, const Range& range) {
    if (auto v = number(key, range)) out = *v;
  }

  std::optional<std::int64_t> integer_value(std::string_view key, std::int64_t lo,
                                      std::int64_t hi = std::numeric_limits<std::int64_t>::max()) {
    const toml::node* n = get(key);
    if (!n) return std::nullopt;
    std::string allowed = "must be " + int_range_text(lo, hi);
    if (!n->is_integer()) fail(key, *n, allowed);
    std::int64_t v = n->as_integer()->get();
    if (v < lo || v > hi) fail(key, *n, allowed);
    return v;
  }
  void integer(std::string_view key, int& out, std::int64_t lo,
               std::int64_t hi = std::numeric_limits<int>::max()) {
    if (auto v = integer_value(key, lo, hi)) out = static_cast<int>(*v);
  }

  void boolean(std::string_view key, bool& out) {
    const toml::node* n = get(key);
    if (!n) return;
    if (!n->is_boolean()) fail(key, *n, "must be true or false");
    out = n->as_boolean()->get();
  }

  std::optional<std::string> text(std::string_view key) {
    const toml::node* n = get(key);
    if (!n) return std::nullopt;
    if (!n->is_string()) fail(key, *n, "must be a string");
    return n->as_string()->get();
  }

  template <class E>
  std::optional<E> choice(std::string_view key, std::initializer_list<std::pair<std::string_view, E>> options) {
    const toml::node* n = get(key);
    if (!n) return std::nullopt;
    std::string names;
    for (const auto& [name, value] : options) names += (names.empty() ? "" : ", ") + std::string(name);
    if (!n->is_string()) fail(key, *n, "must be a string, one of: " + names);
    for (const auto& [name, value] : options)
      if (n->as_string()->get() == name) return value;
    fail(key, *n, "one of: " + names);
  }

  // Unknown keys are errors that list what this section allows.
  void finish() const {
    if (!t_) return;
    for (const auto& [k, n] : *t_) {
      if (std::find(allowed_.begin(), allowed_.end(), k.str()) != allowed_.end()) continue;
      std::string list;
      for (const auto& a : allowed_) list += (list.empty() ? "" : ", ") + a;
      std::string where = path_.empty() ? "at the top level" : "in [" + path_ + "]";
      throw ScenarioError(r_.locate(dotted(k.str()), n), dotted(k.str()), value_text(n),
                          fmt::format("unknown key; allowed {}: {}", where, list));
    }
  }

 private:
  Reader& r_;
  const toml::table* t_;
  std::string path_;
  std::vector<std::string> allowed_;
};

}  // namespace gapflow::scenario_reading

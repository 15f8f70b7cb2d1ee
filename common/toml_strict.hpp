// Strict reading of TOML tables, shared by the study and measured-data loaders:
// a StrictTable knows its allowed keys, so an unknown key (usually a typo) is
// reported first, before any "missing key" it may have caused, and reading a key
// that is not in the list is a programming error, so the list cannot drift from
// the reader. Errors are ScenarioErrors at file:line:column with the key, the
// value as TOML spells it, and what is allowed.
#pragma once

#include "common/input_bounds.hpp"
#include "common/scenario_loader.hpp"

#include <fmt/format.h>
#include <toml++/toml.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <optional>
#include <sstream>
#include <string>
#include <string_view>
#include <vector>

namespace gapflow {

// Shortest text that reads back to the same double (19.4, not toml++'s
// 19.399999999999999), spelled as a float so that TOML does not read an integer.
inline std::string number_text(double v) {
  std::string s = fmt::format("{}", v);
  if (s.find_first_of(".eEn") == std::string::npos) s += ".0";  // 'n': inf, nan
  return s;
}

// The node as JSON spells it (for axes_json).
inline std::string json_text(const toml::node& n) {
  if (auto f = n.as_floating_point()) return number_text(f->get());
  std::ostringstream os;
  os << toml::json_formatter{n, toml::format_flags::none};
  return os.str();
}

// The node as TOML spells it. Strings in JSON's double quotes: valid TOML basic
// strings, and the same quoting the scenario loader's messages use.
inline std::string toml_text(const toml::node& n) {
  if (n.is_string() || n.is_floating_point()) return json_text(n);
  std::ostringstream os;
  n.visit([&](auto&& v) { os << v; });
  return os.str();
}

inline SourceLocation location_of(const std::string& source, const toml::node& n) {
  const auto& b = n.source().begin;
  if (b.line == 0) return {source, 1, 1};
  return {source, static_cast<int>(b.line), static_cast<int>(b.column)};
}

// A TOML table whose keys must all be understood.
class StrictTable {
 public:
  StrictTable(const toml::table* t, std::string path, std::string source, std::vector<std::string> allowed)
      : t_(t), path_(std::move(path)), source_(std::move(source)), allowed_(std::move(allowed)) {
    reject_unknown();
  }

  SourceLocation at(const toml::node& n) const { return location_of(source_, n); }
  SourceLocation here() const { return t_ ? at(*t_) : SourceLocation{source_, 1, 1}; }
  std::string dotted(std::string_view key) const {
    return path_.empty() ? std::string(key) : path_ + "." + std::string(key);
  }

  const toml::node* get(std::string_view key) const {
    if (std::find(allowed_.begin(), allowed_.end(), key) == allowed_.end())
      throw std::logic_error(fmt::format("loader reads '{}' but does not allow it in [{}]", key, path_));
    return t_ ? t_->get(key) : nullptr;
  }
  [[noreturn]] void fail(std::string_view key, const toml::node& n, const std::string& allowed) const {
    throw ScenarioError(at(n), dotted(key), toml_text(n), allowed);
  }
  [[noreturn]] void missing(std::string_view key, const std::string& allowed) const {
    throw ScenarioError(here(), dotted(key), "", allowed);
  }

  std::optional<std::string> text(std::string_view key, bool non_empty = false) {
    const toml::node* n = get(key);
    if (!n) return std::nullopt;
    if (!n->is_string() || (non_empty && n->as_string()->get().empty()))
      fail(key, *n, non_empty ? "must be a non-empty string" : "must be a string");
    return n->as_string()->get();
  }
  std::optional<std::int64_t> integer(std::string_view key, std::int64_t lo,
                                      std::int64_t hi = std::numeric_limits<std::int64_t>::max()) {
    const toml::node* n = get(key);
    if (!n) return std::nullopt;
    if (!n->is_integer() || n->as_integer()->get() < lo || n->as_integer()->get() > hi)
      fail(key, *n, "must be " + int_range_text(lo, hi));
    return n->as_integer()->get();
  }
  // A finite number in [lo, hi] (integers read as numbers).
  std::optional<double> number(std::string_view key, double lo, double hi) {
    const toml::node* n = get(key);
    if (!n) return std::nullopt;
    const std::optional<double> v = n->value<double>();
    if (!n->is_number() || !v || !std::isfinite(*v) || *v < lo || *v > hi)
      fail(key, *n, fmt::format("must be a number in [{}, {}]", lo, hi));
    return v;
  }
  std::optional<bool> boolean(std::string_view key) {
    const toml::node* n = get(key);
    if (!n) return std::nullopt;
    if (!n->is_boolean()) fail(key, *n, "must be true or false");
    return n->as_boolean()->get();
  }
  // A string from a fixed list.
  std::optional<std::string> choice(std::string_view key, const std::vector<std::string>& allowed) {
    const toml::node* n = get(key);
    if (!n) return std::nullopt;
    if (!n->is_string() || std::find(allowed.begin(), allowed.end(), n->as_string()->get()) == allowed.end()) {
      std::string list;
      for (const auto& a : allowed) list += (list.empty() ? "\"" : ", \"") + a + "\"";
      fail(key, *n, "must be one of " + list);
    }
    return n->as_string()->get();
  }
  const toml::table* table(std::string_view key) {
    const toml::node* n = get(key);
    if (n && !n->is_table()) fail(key, *n, fmt::format("must be a table [{}]", dotted(key)));
    return n ? n->as_table() : nullptr;
  }
  const toml::array* array(std::string_view key, const char* of) {
    const toml::node* n = get(key);
    if (n && !n->is_array()) fail(key, *n, fmt::format("must be an array of {}", of));
    return n ? n->as_array() : nullptr;
  }

  void reject_unknown() const {
    if (!t_) return;
    for (const auto& [k, n] : *t_) {
      if (std::find(allowed_.begin(), allowed_.end(), k.str()) != allowed_.end()) continue;
      std::string list;
      for (const auto& a : allowed_) list += (list.empty() ? "" : ", ") + a;
      const std::string where =
          path_.empty() ? "unknown section; allowed at the top level" : "unknown key; allowed in [" + path_ + "]";
      throw ScenarioError(at(n), dotted(k.str()), toml_text(n), fmt::format("{}: {}", where, list));
    }
  }

 private:
  const toml::table* t_;
  std::string path_, source_;
  std::vector<std::string> allowed_;
};

}  // namespace gapflow

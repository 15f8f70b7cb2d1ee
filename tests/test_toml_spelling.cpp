// toml_quote and toml_double write what the loader reads back unchanged: the
// canonical scenario text (and so every stored run's hash) and the twin data
// files are built from them.
#include "common/scenario_loader.hpp"
#include "common/text_file.hpp"
#include "common/toml_spelling.hpp"
#include "tests/test_support.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <string>

namespace {

using gapflow::parse_scenario;
using gapflow::toml_double;
using gapflow::toml_key;
using gapflow::toml_quote;

// The paper's cylinder scenario with its [scenario] description replaced by `value_text`.
std::string cylinder_with_description(const std::string& value_text) {
  std::string text = gapflow::read_input_file(gapflow::testing::source_path("scenarios/paper/cylinder.toml"), "scenario");
  const std::string line = "description = \"Murray 2016 sec. IV: cylinder obstruction, medium spheres, W = 33 mm\"";
  const auto at = text.find(line);
  EXPECT_NE(at, std::string::npos);
  return text.replace(at, line.size(), "description = " + value_text);
}

TEST(TomlSpelling, QuotedStringsReadBackUnchanged) {
  for (const std::string& s : {std::string("plain"), std::string("a \"quoted\" word"), std::string("back\\slash C:\\x"),
                              std::string("two\nlines\tand tab\r"), std::string("bell\x07 and del\x7f"),
                              std::string("unicode: \xc2\xb5m, \xe2\x88\x9a")}) {
    const auto loaded = parse_scenario(cylinder_with_description(toml_quote(s)), "spelling.toml");
    EXPECT_EQ(loaded.def.description, s) << toml_quote(s);
  }
}

TEST(TomlSpelling, KeysAreBareOnlyWhenTomlAllowsIt) {
  EXPECT_EQ(toml_key("W_over_d"), "W_over_d");
  EXPECT_EQ(toml_key("gap-mm"), "gap-mm");
  EXPECT_EQ(toml_key("W over d"), "\"W over d\"");
  EXPECT_EQ(toml_key("gap.mm"), "\"gap.mm\"");  // bare, the dot would make a table
  EXPECT_EQ(toml_key(""), "\"\"");
}

TEST(TomlSpelling, DoublesAreShortestFloatsThatReadBackExactly) {
  EXPECT_EQ(toml_double(1000.0), "1000.0");  // not "1000": TOML would read an integer
  EXPECT_EQ(toml_double(19.4), "19.4");
  EXPECT_EQ(toml_double(std::numeric_limits<double>::infinity()), "inf");
  EXPECT_EQ(toml_double(-std::numeric_limits<double>::infinity()), "-inf");
  EXPECT_EQ(toml_double(std::nan("")), "nan");
  for (const double v : {0.1, 1.0 / 3.0, 6.02214076e23, 1e-300, -2.5e-7, 80.0})
    EXPECT_EQ(std::stod(toml_double(v)), v) << toml_double(v);
  // The canonical scenario text (what scenario_hash reads) spells a whole number as a float.
  const auto loaded = parse_scenario(cylinder_with_description("\"d\""), "spelling.toml", {"obstruction.diameter_mm=81"});
  EXPECT_EQ(loaded.def.obstruction.diameter_mm, 81.0);
  EXPECT_NE(gapflow::canonical_toml(loaded.def).find("\ndiameter_mm = 81.0\n"), std::string::npos);
}

}  // namespace

// JSON spelling of strings and numbers, for the files gapflow writes by hand
// (report plot specs, calibration summaries). JSON has no NaN or infinity:
// missing values are null (Python reads None).
#pragma once

#include <fmt/format.h>

#include <cmath>
#include <string>

namespace gapflow {

inline std::string json_string(const std::string& s) {
  std::string out = "\"";
  for (char c : s) {
    if (c == '"' || c == '\\') {
      out += '\\';
      out += c;
    } else if (static_cast<unsigned char>(c) < 0x20) {
      out += fmt::format("\\u{:04x}", static_cast<unsigned>(c));
    } else {
      out += c;
    }
  }
  return out + "\"";
}

inline std::string json_number(double v) { return std::isfinite(v) ? fmt::format("{}", v) : "null"; }

}  // namespace gapflow

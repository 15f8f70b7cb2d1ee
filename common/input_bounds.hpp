// Input bounds shared by every loader (scenario, study, report, and later calibration):
// numeric ranges that say what they allow, and the size limits of everything gapflow
// reads or expands. One mechanism, so that a limit is stated once and its message
// always reads the same ("must be in [0.1, 1000] (mm)").
//
// Why bounded at all: an unbounded "> 0" lets 1e-320 mm particles, a 1e308 mm board
// or a 1e-9 s step through, and each of those hangs or exhausts memory long before it
// fails. Every range is physical (what the lab set-up could be) and finite.
#pragma once

#include <fmt/format.h>

#include <cstddef>
#include <cstdint>
#include <limits>
#include <string>

namespace gapflow {

inline constexpr double kInf = std::numeric_limits<double>::infinity();

// A closed, open or half-open interval of allowed values, with its unit for messages.
struct Range {
  double lo = -kInf, hi = kInf;
  bool lo_open = false, hi_open = false;
  const char* unit = "";
  bool contains(double v) const {
    return (lo_open ? v > lo : v >= lo) && (hi_open ? v < hi : v <= hi);
  }
  // "> 0 (mm)", "in [0, 60) (deg)", "" for any finite value.
  std::string text() const {
    std::string b;
    if (lo > -kInf && hi < kInf)
      b = fmt::format("in {}{}, {}{}", lo_open ? '(' : '[', lo, hi, hi_open ? ')' : ']');
    else if (lo > -kInf)
      b = fmt::format("{} {}", lo_open ? ">" : ">=", lo);
    else if (hi < kInf)
      b = fmt::format("{} {}", hi_open ? "<" : "<=", hi);
    if (*unit) b += fmt::format("{}({})", b.empty() ? "" : " ", unit);
    return b;
  }
};

inline Range above(double lo, const char* unit = "") { return {lo, kInf, true, false, unit}; }
inline Range at_least(double lo, const char* unit = "") { return {lo, kInf, false, false, unit}; }
inline Range closed(double lo, double hi, const char* unit = "") { return {lo, hi, false, false, unit}; }
inline Range upper_open(double lo, double hi, const char* unit = "") { return {lo, hi, false, true, unit}; }
inline Range lower_open(double lo, double hi, const char* unit = "") { return {lo, hi, true, false, unit}; }
inline Range any(const char* unit = "") { return {-kInf, kInf, false, false, unit}; }

inline std::string int_range_text(std::int64_t lo, std::int64_t hi) {
  if (hi == std::numeric_limits<std::int64_t>::max()) return fmt::format("an integer >= {}", lo);
  return fmt::format("an integer in [{}, {}]", lo, hi);
}

// ---------------------------------------------------------------- physical limits (lab units)

inline constexpr double kMaxLengthMm = 100000;     // any length or distance on the board: 100 m
inline constexpr double kMinDiameterMm = 0.1;      // particle diameter
inline constexpr double kMaxDiameterMm = 1000;
inline constexpr double kMinFeatureD = 0.1;        // smallest obstruction edge / size, in particle diameters
inline constexpr double kMaxAmplitudeMm = 100;     // shaking amplitude
inline constexpr double kMaxFrequencyHz = 1000;
inline constexpr double kMaxTimeS = 86400;         // any duration in a scenario: one day
inline constexpr double kMinTimeStepS = 1e-5;      // engine time steps
inline constexpr double kMaxTimeStepS = 0.1;

// ---------------------------------------------------------------- sizes

inline constexpr std::size_t kMaxInputFileBytes = 4u << 20;  // a scenario, study or study-info file
inline constexpr std::int64_t kMaxPackingSites = 20000000;   // lattice sites scanned to pack the particles
inline constexpr std::int64_t kMaxReplicates = 10000;        // per point and model
inline constexpr std::int64_t kMaxAxisValues = 10000;        // values of one sweep axis
inline constexpr std::int64_t kMaxStudyJobs = 100000;        // jobs of a whole study (product of all axes ...)

}  // namespace gapflow

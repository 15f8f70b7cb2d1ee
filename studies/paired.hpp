// Paired comparisons of a point with its baseline (common random numbers).
//
// A study gives replicate r of every point the same run.seed and run.replicate, and the
// particle sizes and placements come from streams keyed by (seed, replicate, particle) alone
// (common/random.hpp), so replicate r at an obstruction position and replicate r at the
// no-obstruction baseline start from the same particle set. Their J values are pairs, and
// J/J_0 can be estimated paired (common/paired_ratio.hpp). The runs are chaotic, so how much
// the pairing helps is measured, not assumed: `gapflow report RESULTS --pairing` prints the
// correlation and the interval widths per point (pairing_table).
#pragma once

#include "studies/analysis.hpp"

#include <string>
#include <vector>

namespace gapflow {

struct ReportData;
struct TextTable;

// The J values of the runs both points have (same run.seed and run.replicate, the chosen J
// defined in both), in key order; a[i] from `point`, b[i] from `baseline`.
struct PairedValues {
  std::vector<double> a, b;
  std::size_t only_a = 0, only_b = 0;  // runs with J at one point only (left out of a, b)
  bool exact() const { return only_a == 0 && only_b == 0; }
};
PairedValues pair_by_replicate(const PointStatistics& point, const PointStatistics& baseline, JKind kind);

// One point against its baseline, both ways.
struct PairingRow {
  std::string series, model, point_label;
  double d_over_d = kNaN;
  PairedValues pairs;
  RatioComparison unpaired;         // all runs with J, as independent samples (bootstrap + Welch)
  RatioComparison paired;           // the common runs only (Fieller + paired t)
  double variance_factor = kNaN;    // paired_variance_factor of the common runs
  double width_ratio = kNaN;        // paired interval width / unpaired interval width
  bool used = false;                // the report uses the paired one ([report] pairing = "paired" and pairs.exact())
};
std::vector<PairingRow> pairing_rows(const ReportData& data, JKind kind);
TextTable pairing_table(const std::vector<PairingRow>& rows, JKind kind);

}  // namespace gapflow

#include "studies/paired.hpp"

#include "common/paired_ratio.hpp"
#include "studies/report.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <map>

namespace gapflow {

PairedValues pair_by_replicate(const PointStatistics& point, const PointStatistics& baseline, JKind kind) {
  std::map<ReplicateKey, double> at_baseline;
  const std::vector<ReplicateKey>& kb = j_keys(baseline, kind);
  const std::vector<double>& vb = j_values(baseline, kind);
  for (std::size_t i = 0; i < kb.size(); ++i) at_baseline.emplace(kb[i], vb[i]);
  std::map<ReplicateKey, double> at_point;
  const std::vector<ReplicateKey>& ka = j_keys(point, kind);
  const std::vector<double>& va = j_values(point, kind);
  for (std::size_t i = 0; i < ka.size(); ++i) at_point.emplace(ka[i], va[i]);
  PairedValues p;
  for (const auto& [key, j] : at_point) {
    auto it = at_baseline.find(key);
    if (it == at_baseline.end()) {
      ++p.only_a;
      continue;
    }
    p.a.push_back(j);
    p.b.push_back(it->second);
  }
  p.only_b = at_baseline.size() - p.a.size();
  return p;
}

std::vector<PairingRow> pairing_rows(const ReportData& data, JKind kind) {
  const bool pairing_asked = data.study.report.pairing == Pairing::when_exact;
  std::vector<PairingRow> rows;
  for (const ReportPoint& p : data.points) {
    if (is_baseline(data, p)) continue;
    const ReportPoint* b = baseline_for(data, p);
    if (!b) continue;
    PairingRow r;
    r.series = p.series, r.model = p.model, r.point_label = p.point_label;
    r.d_over_d = p.stats.distance_over_d;
    r.pairs = pair_by_replicate(p.stats, b->stats, kind);
    r.unpaired = compare_to_baseline(p.stats, b->stats, kind, {}, Pairing::never);
    r.paired = compare_ratio_paired(r.pairs.a, r.pairs.b);
    r.variance_factor = paired_variance_factor(r.pairs.a, r.pairs.b);
    if (r.paired.ratio_ci.valid() && r.unpaired.ratio_ci.valid() && r.unpaired.ratio_ci.width() > 0)
      r.width_ratio = r.paired.ratio_ci.width() / r.unpaired.ratio_ci.width();
    r.used = pairing_asked && r.pairs.exact() && r.pairs.a.size() >= 2;
    rows.push_back(std::move(r));
  }
  return rows;
}

TextTable pairing_table(const std::vector<PairingRow>& rows, JKind kind) {
  TextTable t;
  t.title = fmt::format("{}/{}_0 paired by replicate against unpaired", to_string(kind), to_string(kind));
  t.header = {"series", "model", "point", "pairs", "only pt/base", "rho", "unpaired [95% CI]", "paired [95% CI]",
              "width p/u", "var factor", "report uses"};
  for (const PairingRow& r : rows)
    t.rows.push_back({r.series, r.model, r.point_label, fmt::format("{}", r.pairs.a.size()),
                      fmt::format("{}/{}", r.pairs.only_a, r.pairs.only_b), fmt_num(r.paired.correlation, 2),
                      fmt_num(r.unpaired.ratio, 4) + " " + fmt_interval(r.unpaired.ratio_ci, 4),
                      fmt_num(r.paired.ratio, 4) + " " + fmt_interval(r.paired.ratio_ci, 4),
                      fmt_num(r.width_ratio, 3), fmt_num(r.variance_factor, 3), r.used ? "paired" : "unpaired"});
  // Per model: the middle of the measured correlations and factors (points with >= 3 pairs).
  std::map<std::string, std::pair<std::vector<double>, std::vector<double>>> by_model;
  for (const PairingRow& r : rows)
    if (r.pairs.a.size() >= 3 && std::isfinite(r.paired.correlation)) {
      by_model[r.model].first.push_back(r.paired.correlation);
      by_model[r.model].second.push_back(r.variance_factor);
    }
  for (const auto& [model, v] : by_model)
    t.notes.push_back(fmt::format("model {}: {} points with >= 3 pairs; median rho {}, range [{}, {}]; median var factor {}",
                                  model, v.first.size(), fmt_num(median(v.first), 2),
                                  fmt_num(*std::min_element(v.first.begin(), v.first.end()), 2),
                                  fmt_num(*std::max_element(v.first.begin(), v.first.end()), 2),
                                  fmt_num(median(v.second), 3)));
  t.notes.push_back(
      "unpaired: all runs with J, percentile bootstrap of the ratio of means (+ Welch); paired: the runs with the "
      "same seed and replicate at both points, Fieller's interval (+ paired t). width p/u = paired / unpaired "
      "interval width; var factor = variance of the ratio paired / as independent samples on the same pairs "
      "(delta method; ~1 - rho). With [report] pairing = \"paired\" the report uses the paired comparison where the "
      "replicate sets match exactly (only pt/base = 0/0); by default it stays unpaired.");
  return t;
}

}  // namespace gapflow

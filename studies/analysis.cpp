#include "studies/analysis.hpp"

#include "common/measurement.hpp"
#include "common/paired_ratio.hpp"
#include "studies/paired.hpp"
#include "common/random.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>

namespace gapflow {

namespace {

double mean_or_nan(const std::vector<double>& v) {
  return v.empty() ? kNaN : std::accumulate(v.begin(), v.end(), 0.0) / static_cast<double>(v.size());
}

// A different bootstrap stream for each J kind, derived from the one seed.
BootstrapOptions derived(BootstrapOptions opt, std::uint64_t tag) {
  opt.seed = mix_seed(opt.seed, tag);
  return opt;
}

}  // namespace

AvalancheStatistics avalanche_statistics(const std::vector<RunRecord>& runs, const TailCheckOptions& opt) {
  AvalancheStatistics a;
  std::vector<double> sizes;
  std::vector<bool> censored;
  for (const RunRecord& r : runs)
    for (const Avalanche& av : r.avalanches) {
      ++a.n_all;
      if (av.first) {  // shaped by the initial packing, not by the steady flow
        ++a.n_first_excluded;
        continue;
      }
      sizes.push_back(av.size);
      censored.push_back(av.censored);
      if (!av.censored) a.sizes.push_back(av.size);
    }
  a.size = censored_exponential_mean(sizes, censored);
  a.tail = geometric_tail_check(a.sizes, opt);
  // Threshold at the mean: ~e^-1 of a geometric sample lies above it, enough to test, and
  // far enough up to leave out the small-size deficit seen in long runs.
  // <s> is the censoring-aware mean of the table, the one the threshold is named after.
  if (a.size.mean >= 1) a.upper_tail = geometric_upper_tail_check(a.sizes, static_cast<int>(std::ceil(a.size.mean)), opt);
  return a;
}

ClogStatistics clog_statistics(const std::vector<RunRecord>& runs, double hill_top_fraction) {
  ClogStatistics c;
  std::vector<double> all, completed, fronts_d;
  for (const RunRecord& r : runs)
    for (const Clog& cl : r.clogs) {
      all.push_back(cl.duration);
      if (const auto site = clog_site(cl, r.gap_m, r.diameter_m)) {
        fronts_d.push_back(*cl.front_m / r.diameter_m);
        if (!cl.on_obstruction) ++c.n_contact_not_measured;
        switch (*site) {
          case ClogSite::gap: ++c.n_at_gap; break;
          case ClogSite::obstruction: ++c.n_on_obstruction; break;
          case ClogSite::upstream: ++c.n_upstream; break;
        }
      }
      if (cl.censored) {
        ++c.n_censored;
      } else {
        completed.push_back(cl.duration);
      }
    }
  c.n = all.size();
  if (c.n == 0) return c;
  c.n_located = fronts_d.size();
  if (!fronts_d.empty()) c.median_front_d = median(fronts_d);
  c.fraction_censored = static_cast<double>(c.n_censored) / static_cast<double>(c.n);
  c.mean_all_s = mean_or_nan(all);
  c.max_s = *std::max_element(all.begin(), all.end());
  c.mean_uncensored_s = mean_or_nan(completed);
  c.median_uncensored_s = median(completed);
  c.tail = hill_estimator(completed, hill_top_fraction);
  c.heavy_tail = c.tail.valid() && c.tail.alpha < 2.0;
  return c;
}

FlowDecomposition decompose_flow(const std::vector<RunRecord>& runs) {
  FlowDecomposition f;
  double sum_size = 0, sum_duration = 0, sum_gaps = 0, sum_clog = 0;
  for (const RunRecord& r : runs) {
    for (const Avalanche& a : r.avalanches) {
      ++f.n_avalanches;
      sum_size += a.size;
      sum_duration += a.t_end - a.t_start;
      sum_gaps += a.size - 1;  // inter-crossing intervals inside the avalanche
    }
    for (const Clog& c : r.clogs)
      if (!c.censored) {
        ++f.n_clogs;
        sum_clog += c.duration;
      }
  }
  if (f.n_avalanches == 0 || sum_gaps <= 0 || sum_duration <= 0) return f;
  const double na = static_cast<double>(f.n_avalanches), nc = static_cast<double>(f.n_clogs);
  f.tau_s = sum_duration / sum_gaps;
  f.mean_size = sum_size / na;
  const double total_flow = sum_duration + na * f.tau_s;  // sum of T_flow
  const double total_clog = sum_clog - nc * f.tau_s;      // sum of T_clog
  f.mean_t_flow_s = total_flow / na;
  f.j_flow = f.mean_size / f.mean_t_flow_s;
  f.mean_t_clog_s = f.n_clogs > 0 ? total_clog / nc : kNaN;
  f.j_cycle = f.mean_size / (f.mean_t_flow_s + (f.n_clogs > 0 ? f.mean_t_clog_s : 0.0));
  f.j_total = sum_size / (total_flow + total_clog);
  f.valid = true;
  return f;
}

RegimeFractions regime_fractions(const std::vector<RunRecord>& runs, double majority) {
  RegimeFractions g;
  g.n = runs.size();
  if (g.n == 0) return g;
  for (const RunRecord& r : runs) {
    (r.regime == Regime::continuous     ? g.continuous
     : r.regime == Regime::intermittent ? g.intermittent
                                        : g.clogged) += 1.0;
  }
  const double n = static_cast<double>(g.n);
  g.continuous /= n;
  g.intermittent /= n;
  g.clogged /= n;
  g.label = g.continuous > majority     ? to_string(Regime::continuous)
            : g.intermittent > majority ? to_string(Regime::intermittent)
            : g.clogged > majority      ? to_string(Regime::clogged)
                                        : "mixed";
  return g;
}

namespace {

void fill_identity_and_counts(const std::vector<RunRecord>& runs, PointStatistics& p) {
  const RunRecord& first = runs.front();
  p.scenario_name = first.scenario_name;
  if (first.diameter_m > 0) {
    p.w_over_d = first.gap_m / first.diameter_m;
    p.distance_over_d = first.distance_m / first.diameter_m;
    p.j_star_factor = std::sqrt(first.diameter_m / 9.81);  // README: J*sqrt(d/g), g = 9.81 m/s^2
  }
  std::vector<double> all_passed, passed_fraction, sim, wall;
  for (const RunRecord& r : runs) {
    // With re-injection `passed` counts crossings (a sphere can cross again): no discharge to measure.
    if (r.reinjected == 0) {
      all_passed.push_back(r.particles > 0 && r.passed == r.particles ? 1.0 : 0.0);
      passed_fraction.push_back(r.particles > 0 ? static_cast<double>(r.passed) / r.particles : 0.0);
    }
    sim.push_back(r.sim_time_s);
    wall.push_back(r.wall_time_s);
    p.escaped_total += r.escaped;
    p.max_conservation_error = std::max(p.max_conservation_error, r.max_conservation_error);
    const ReplicateKey key{r.base_seed, r.replicate};
    if (r.j_paper) p.j_paper_values.push_back(*r.j_paper), p.j_paper_keys.push_back(key);
    if (r.j_flowing) p.j_flowing_values.push_back(*r.j_flowing), p.j_flowing_keys.push_back(key);
    if (r.j_mid) p.j_mid_values.push_back(*r.j_mid), p.j_mid_keys.push_back(key);
  }
  p.all_passed_fraction = mean_or_nan(all_passed);
  p.mean_passed_fraction = mean_or_nan(passed_fraction);
  if (!passed_fraction.empty()) {
    const auto [lo, hi] = std::minmax_element(passed_fraction.begin(), passed_fraction.end());
    p.min_passed_fraction = *lo, p.max_passed_fraction = *hi;
  }
  p.mean_sim_time_s = mean_or_nan(sim);
  p.mean_wall_time_s = mean_or_nan(wall);
}

}  // namespace

PointStatistics analyze_point(const std::vector<RunRecord>& runs, const AnalysisOptions& opt) {
  PointStatistics p;
  p.n_runs = runs.size();
  if (runs.empty()) return p;
  fill_identity_and_counts(runs, p);
  p.j_paper = describe(p.j_paper_values, derived(opt.bootstrap, 1));
  p.j_flowing = describe(p.j_flowing_values, derived(opt.bootstrap, 2));
  p.j_mid = describe(p.j_mid_values, derived(opt.bootstrap, 3));
  p.avalanches = avalanche_statistics(runs, opt.tail);
  p.clogs = clog_statistics(runs, opt.hill_top_fraction);
  p.decomposition = decompose_flow(runs);
  p.regime = regime_fractions(runs, opt.majority);
  return p;
}

namespace {
// Each flow rate's name in study files and on the command line, and in tables and reports.
struct JKindNames {
  JKind kind;
  const char* option;
  const char* label;
};
constexpr JKindNames kJKindNames[] = {{JKind::paper, "paper", "J_paper"},
                                      {JKind::flowing, "flowing", "J_flowing"},
                                      {JKind::mid, "mid", "J_mid"}};
const JKindNames& names_of(JKind k) {
  for (const JKindNames& n : kJKindNames)
    if (n.kind == k) return n;
  return kJKindNames[0];  // unreachable: every enumerator is in the table
}
}  // namespace

const char* option_name(JKind k) { return names_of(k).option; }
const char* to_string(JKind k) { return names_of(k).label; }

const std::vector<std::string>& jkind_option_names() {
  static const std::vector<std::string> names = [] {
    std::vector<std::string> v;
    for (const JKindNames& n : kJKindNames) v.push_back(n.option);
    return v;
  }();
  return names;
}

std::optional<JKind> jkind_from_option(std::string_view name) {
  for (const JKindNames& n : kJKindNames)
    if (name == n.option) return n.kind;
  return std::nullopt;
}

const SampleStatistics& j_stats(const PointStatistics& s, JKind k) {
  return k == JKind::paper ? s.j_paper : k == JKind::flowing ? s.j_flowing : s.j_mid;
}
const std::vector<double>& j_values(const PointStatistics& s, JKind k) {
  return k == JKind::paper ? s.j_paper_values : k == JKind::flowing ? s.j_flowing_values : s.j_mid_values;
}
const std::vector<ReplicateKey>& j_keys(const PointStatistics& s, JKind k) {
  return k == JKind::paper ? s.j_paper_keys : k == JKind::flowing ? s.j_flowing_keys : s.j_mid_keys;
}

RatioComparison compare_to_baseline(const PointStatistics& point, const PointStatistics& baseline, JKind kind,
                                    const BootstrapOptions& opt, Pairing pairing) {
  if (pairing == Pairing::when_exact) {
    const PairedValues pairs = pair_by_replicate(point, baseline, kind);
    if (pairs.exact() && pairs.a.size() >= 2) return compare_ratio_paired(pairs.a, pairs.b, opt.level);
  }
  return compare_ratio_of_means(j_values(point, kind), j_values(baseline, kind), opt);
}

}  // namespace gapflow

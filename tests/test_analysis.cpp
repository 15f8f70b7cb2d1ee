// Per-point analysis of run records, on synthetic records whose answers are known.
#include "common/measurement.hpp"
#include "common/random.hpp"
#include "studies/analysis.hpp"

#include <gtest/gtest.h>

#include <cmath>

using namespace gapflow;

namespace {

// A record from crossing times (s), segmented by the project's own segment_flow (clog
// timeout 1 s); J_paper = N / t_last when everything passed, J_flowing for a run without
// clogs = (n - 1) / (t_last - t_first) (README definitions).
RunRecord record_from(const std::vector<double>& times, int particles, double t_end, int replicate = 0) {
  RunRecord r;
  r.scenario_name = "synthetic";
  r.replicate = replicate;
  r.diameter_m = 0.00775;
  r.gap_m = 0.033;
  r.particles = particles;
  r.passed = static_cast<int>(times.size());
  r.sim_time_s = t_end;
  r.wall_time_s = 2.0;
  for (std::size_t i = 0; i < times.size(); ++i) r.crossings.push_back({static_cast<int>(i), times[i], 0.0});
  segment_flow(r.crossings, 1.0, t_end, r.avalanches, r.clogs);
  if (r.passed == particles && !times.empty()) r.j_paper = particles / times.back();
  if (r.clogs.empty() && times.size() >= 2) r.j_flowing = (times.size() - 1) / (times.back() - times.front());
  r.regime = r.clogs.empty() ? Regime::continuous : Regime::intermittent;
  return r;
}

// K avalanches of s crossings, period tau, separated by clogs of `clog` s (crossing to
// crossing); the first crossing is one period after release.
std::vector<double> periodic(int avalanches, int s, double tau, double clog) {
  std::vector<double> t;
  double now = tau;
  for (int a = 0; a < avalanches; ++a) {
    for (int i = 0; i < s; ++i) {
      t.push_back(now);
      now += tau;
    }
    now += clog - tau;  // the last crossing -> next first crossing takes `clog`
  }
  return t;
}

}  // namespace

TEST(Decomposition, ReproducesJFlowingAndJPaperOnAPeriodicContinuousRun) {
  const double tau = 0.04;
  const RunRecord r = record_from(periodic(1, 500, tau, 0.0), 500, 500 * tau);
  ASSERT_TRUE(r.clogs.empty());
  const FlowDecomposition d = decompose_flow({r});
  ASSERT_TRUE(d.valid);
  EXPECT_NEAR(d.tau_s, tau, 1e-12);
  EXPECT_NEAR(d.j_flow, *r.j_flowing, 1e-9);
  EXPECT_NEAR(d.j_cycle, d.j_flow, 1e-12);
  EXPECT_NEAR(d.j_total, *r.j_paper, 1e-9);
  EXPECT_NEAR(*r.j_paper, 1.0 / tau, 1e-9);
}

TEST(Decomposition, ReproducesJPaperAndTheFlowingRateOnPeriodicIntermittentRuns) {
  // 5 avalanches of 20, period 0.05 s, clogs of 2 s; three such runs.
  const double tau = 0.05, clog = 2.0;
  const int k = 5, s = 20;
  const auto times = periodic(k, s, tau, clog);
  std::vector<RunRecord> runs;
  for (int i = 0; i < 3; ++i) runs.push_back(record_from(times, k * s, times.back(), i));
  ASSERT_EQ(runs[0].clogs.size(), 4u);
  ASSERT_EQ(runs[0].avalanches.size(), 5u);
  const FlowDecomposition d = decompose_flow(runs);
  ASSERT_TRUE(d.valid);
  EXPECT_EQ(d.n_avalanches, 15u);
  EXPECT_EQ(d.n_clogs, 12u);
  EXPECT_NEAR(d.mean_size, s, 1e-12);
  EXPECT_NEAR(d.mean_t_flow_s, s * tau, 1e-12);
  EXPECT_NEAR(d.mean_t_clog_s, clog - tau, 1e-12);
  EXPECT_NEAR(d.j_flow, 1.0 / tau, 1e-9);                               // the rate while flowing
  EXPECT_NEAR(d.j_total, *runs[0].j_paper, 1e-9);                       // N / t_last, exactly
  EXPECT_NEAR(d.j_cycle, s / (s * tau + clog - tau), 1e-9);             // steady state, one clog per avalanche
  EXPECT_LT(d.j_cycle, d.j_total);  // 5 avalanches share 4 clogs: the finite run is a bit faster
}

TEST(Decomposition, NeedsAnAvalancheOfAtLeastTwo) {
  EXPECT_FALSE(decompose_flow({}).valid);
  EXPECT_FALSE(decompose_flow({record_from({0.5}, 1, 0.5)}).valid);
}

TEST(Avalanches, ExcludeTheFirstAndUseTheCensoringAwareMean) {
  // Geometric sizes (mean 8) split into runs; each run starts with a huge "first" avalanche
  // and ends with one that may be cut (censored) by the end of the run.
  RandomStream rs(41);
  const double log_q = std::log1p(-1.0 / 8.0);
  auto draw = [&] { return 1 + static_cast<int>(std::floor(std::log1p(-rs.uniform()) / log_q)); };
  std::vector<RunRecord> runs(60);
  for (RunRecord& r : runs) {
    r.avalanches.push_back({1000, 0, 1, true, false});
    for (int i = 0; i < 10; ++i) r.avalanches.push_back({draw(), 0, 1, false, false});
    // The run ends after `cut` crossings of the last avalanche, independently of its size.
    const int full = draw(), cut = 1 + static_cast<int>(rs.uniform() * 16);
    if (cut < full) {
      r.avalanches.push_back({cut, 0, 1, false, true});
    } else {
      r.avalanches.push_back({full, 0, 1, false, false});
    }
  }
  const AvalancheStatistics a = avalanche_statistics(runs);
  EXPECT_EQ(a.n_first_excluded, 60u);
  EXPECT_EQ(a.n_all, 60u * 12u);
  EXPECT_GT(a.size.n_censored, 15u);
  EXPECT_TRUE(a.size.ci95.contains(8.0)) << a.size.mean << " [" << a.size.ci95.lo << ", " << a.size.ci95.hi << "]";
  EXPECT_LT(a.size.naive_mean, a.size.mean);
  EXPECT_TRUE(a.tail.tested);
  EXPECT_TRUE(a.tail.consistent) << a.tail.p_value;
  EXPECT_EQ(a.tail.law, "geometric");
}

// Where the clogs formed (clog_site): one of each site, one located by its front distance
// alone (a record made before obstruction contact was measured), one not located at all.
TEST(Clogs, CountsEachSiteAndWhatWasLocatedByDistanceOnly) {
  RunRecord r;
  r.diameter_m = 0.00775;
  r.gap_m = 0.033;
  const double d = r.diameter_m;
  r.clogs = {{0, 2, false, 0.5 * d, true},   // leans on the obstruction
             {3, 2, false, 0.5 * d, false},  // across the gap
             {6, 2, false, 10 * d, false},   // mouth empty, no lean
             {9, 2, false, 10 * d},          // front only: upstream by distance
             {12, 2, true}};                 // not located
  const ClogStatistics c = clog_statistics({r});
  EXPECT_EQ(c.n, 5u);
  EXPECT_EQ(c.n_located, 4u);
  EXPECT_EQ(c.n_on_obstruction, 1u);
  EXPECT_EQ(c.n_at_gap, 1u);
  EXPECT_EQ(c.n_upstream, 2u);
  EXPECT_EQ(c.n_contact_not_measured, 1u);
  EXPECT_NEAR(c.median_front_d, (0.5 + 10) / 2, 1e-12);
}

TEST(Clogs, MeanMedianCensoringAndTail) {
  std::vector<RunRecord> runs(2);
  RandomStream rs(43);
  // Pareto durations (x_m = 1 s, alpha = 1.2) plus one censored permanent clog of 30 s.
  for (int i = 0; i < 500; ++i) runs[i % 2].clogs.push_back({0, std::pow(1.0 - rs.uniform(), -1 / 1.2), false, std::nullopt});
  runs[1].clogs.push_back({0, 30.0, true, std::nullopt});
  const ClogStatistics c = clog_statistics(runs);
  EXPECT_EQ(c.n, 501u);
  EXPECT_EQ(c.n_censored, 1u);
  EXPECT_NEAR(c.fraction_censored, 1.0 / 501, 1e-12);
  EXPECT_NEAR(c.median_uncensored_s, std::pow(2.0, 1 / 1.2), 0.15);  // Pareto median x_m 2^(1/alpha)
  EXPECT_GE(c.max_s, 30.0);
  ASSERT_TRUE(c.tail.valid());
  EXPECT_NEAR(c.tail.alpha, 1.2, 3 * c.tail.alpha_se);
  EXPECT_TRUE(c.heavy_tail);
}

TEST(Regime, FractionsAndLabel) {
  std::vector<RunRecord> runs(4);
  runs[3].regime = Regime::intermittent;
  RegimeFractions g = regime_fractions(runs);
  EXPECT_DOUBLE_EQ(g.continuous, 0.75);
  EXPECT_DOUBLE_EQ(g.intermittent, 0.25);
  EXPECT_EQ(g.label, "continuous");
  runs[2].regime = Regime::clogged;
  g = regime_fractions(runs);
  EXPECT_EQ(g.label, "mixed");  // 2 / 1 / 1: no majority
}

// passed/N describes a discharge only without re-injection, where `passed` counts
// crossings and can equal (or pass) N by chance.
TEST(AnalyzePoint, PassedFractionsLeaveOutReinjectedRuns) {
  RunRecord emptied = record_from({0.5, 1.0, 1.5, 2.0}, 4, 2.5);
  RunRecord half = record_from({0.5, 1.0}, 4, 2.5);
  RunRecord reinjected = record_from({0.5, 1.0, 1.5, 2.0}, 4, 2.5);
  reinjected.reinjected = 4;
  const PointStatistics p = analyze_point({emptied, half, reinjected});
  EXPECT_DOUBLE_EQ(p.all_passed_fraction, 0.5);
  EXPECT_DOUBLE_EQ(p.mean_passed_fraction, 0.75);
  const PointStatistics only = analyze_point({reinjected});
  EXPECT_TRUE(std::isnan(only.all_passed_fraction));
  EXPECT_TRUE(std::isnan(only.mean_passed_fraction));
}

TEST(AnalyzePoint, GathersEverythingAndComparesToABaseline) {
  // Baseline: continuous runs with period ~0.05 s; "obstruction": period ~0.04 s (25 % faster).
  RandomStream rs(47);
  auto make = [&](double tau0, int n_runs) {
    std::vector<RunRecord> runs;
    for (int i = 0; i < n_runs; ++i) {
      const double tau = tau0 * (1.0 + 0.05 * rs.normal());
      runs.push_back(record_from(periodic(1, 200, tau, 0.0), 200, 200 * tau, i));
    }
    return runs;
  };
  const auto base_runs = make(0.05, 12), obst_runs = make(0.04, 12);
  const PointStatistics base = analyze_point(base_runs), obst = analyze_point(obst_runs);
  EXPECT_EQ(base.n_runs, 12u);
  EXPECT_EQ(base.j_paper_values.size(), 12u);
  EXPECT_DOUBLE_EQ(base.all_passed_fraction, 1.0);
  EXPECT_DOUBLE_EQ(base.mean_passed_fraction, 1.0);
  EXPECT_EQ(base.escaped_total, 0);
  EXPECT_DOUBLE_EQ(base.mean_wall_time_s, 2.0);
  EXPECT_NEAR(base.w_over_d, 0.033 / 0.00775, 1e-12);
  EXPECT_NEAR(base.j_star_factor, std::sqrt(0.00775 / 9.81), 1e-12);
  EXPECT_NEAR(base.j_paper.t.mean, 20.0, 1.0);
  EXPECT_TRUE(base.j_paper.bootstrap.valid());
  EXPECT_EQ(base.regime.label, "continuous");
  EXPECT_TRUE(base.decomposition.valid);
  EXPECT_EQ(base.clogs.n, 0u);

  const RatioComparison up = compare_to_baseline(obst, base);
  EXPECT_EQ(up.verdict, Verdict::significantly_above);
  EXPECT_TRUE(up.ratio_ci.contains(1.25)) << up.ratio_ci.lo << " " << up.ratio_ci.hi;
  EXPECT_LT(up.welch.p_two_sided, 1e-3);
  const RatioComparison same = compare_to_baseline(analyze_point(make(0.05, 12)), base, JKind::flowing);
  EXPECT_EQ(same.verdict, Verdict::not_distinguishable);
  EXPECT_EQ(analyze_point({}).n_runs, 0u);
}

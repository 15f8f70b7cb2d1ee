// Paired comparisons (common random numbers): Fieller's interval of a ratio of paired means
// (common/paired_ratio.hpp) and the pairing of a point with its baseline by replicate
// (studies/paired.hpp, compare_to_baseline).
#include "common/paired_ratio.hpp"
#include "common/random.hpp"
#include "studies/analysis.hpp"
#include "studies/paired.hpp"
#include "studies/report.hpp"
#include "studies/study.hpp"
#include "tests/test_support.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>

using namespace gapflow;

namespace {

// n pairs (a, b) from a bivariate normal law: means mu_a, mu_b, coefficients of variation cv,
// correlation rho.
void draw_pairs(RandomStream& rs, int n, double mu_a, double mu_b, double cv, double rho, std::vector<double>& a,
                std::vector<double>& b) {
  a.resize(static_cast<std::size_t>(n)), b.resize(static_cast<std::size_t>(n));
  for (int i = 0; i < n; ++i) {
    const double z1 = rs.normal(), z2 = rho * z1 + std::sqrt(1 - rho * rho) * rs.normal();
    a[static_cast<std::size_t>(i)] = mu_a * (1 + cv * z1);
    b[static_cast<std::size_t>(i)] = mu_b * (1 + cv * z2);
  }
}

struct Coverage {
  double covered = 0, paired_width = 0, unpaired_width = 0, variance_factor = 0;
};

// Over `reps` synthetic comparisons: share of Fieller intervals holding the true ratio, and the
// mean widths of the paired and the unpaired (bootstrap) intervals and the variance factor.
Coverage simulate(int reps, int n, double rho, bool with_unpaired, std::uint64_t seed) {
  const double mu_a = 10.5, mu_b = 10.0, truth = mu_a / mu_b;
  RandomStream rs(seed);
  Coverage c;
  std::vector<double> a, b;
  BootstrapOptions bo;
  bo.resamples = 400;
  for (int k = 0; k < reps; ++k) {
    draw_pairs(rs, n, mu_a, mu_b, 0.1, rho, a, b);
    const RatioComparison p = compare_ratio_paired(a, b);
    c.covered += p.ratio_ci.contains(truth) ? 1 : 0;
    c.paired_width += p.ratio_ci.width();
    c.variance_factor += paired_variance_factor(a, b);
    if (with_unpaired) {
      bo.seed = mix_seed(seed, static_cast<std::uint64_t>(k));
      c.unpaired_width += compare_ratio_of_means(a, b, bo).ratio_ci.width();
    }
  }
  c.covered /= reps, c.paired_width /= reps, c.unpaired_width /= reps, c.variance_factor /= reps;
  return c;
}

}  // namespace

TEST(PairedRatio, FiellerCoversTheTrueRatioAtTheNominalRate) {
  // Exact for bivariate-normal pairs: 2000 repetitions give a binomial sd of 0.49 %, so
  // [93.5 %, 96.5 %] is three of them around 95 %. At 10 pairs too (the exactness is not asymptotic).
  for (double rho : {0.0, 0.3, 0.8}) {
    const Coverage c = simulate(2000, 20, rho, false, 11);
    EXPECT_GT(c.covered, 0.935) << "rho " << rho;
    EXPECT_LT(c.covered, 0.965) << "rho " << rho;
  }
  const Coverage small = simulate(2000, 10, 0.5, false, 12);
  EXPECT_GT(small.covered, 0.935);
  EXPECT_LT(small.covered, 0.965);
}

TEST(PairedRatio, NarrowerThanUnpairedWhenPositivelyCorrelated) {
  const Coverage strong = simulate(300, 20, 0.6, true, 21);
  // Width scales as sqrt(variance factor) ~ sqrt(1 - rho) = 0.63 (plus the bootstrap's own narrowness).
  EXPECT_LT(strong.paired_width, 0.8 * strong.unpaired_width);
  EXPECT_NEAR(strong.variance_factor, 0.4, 0.05);
  // Without correlation there is nothing to gain: the factor is ~1 and the widths are alike.
  const Coverage none = simulate(300, 20, 0.0, true, 22);
  EXPECT_NEAR(none.variance_factor, 1.0, 0.05);
  EXPECT_GT(none.paired_width, 0.9 * none.unpaired_width);
}

TEST(PairedRatio, VerdictIsThePairedTTestAndMatchesTheInterval) {
  RandomStream rs(31);
  std::vector<double> a, b;
  int above = 0;
  for (int k = 0; k < 300; ++k) {
    draw_pairs(rs, 12, 10.3, 10.0, 0.05, 0.7, a, b);
    const RatioComparison r = compare_ratio_paired(a, b);
    ASSERT_TRUE(r.paired);
    ASSERT_TRUE(r.ratio_ci.valid());
    const bool excludes_one = r.ratio_ci.lo > 1 || r.ratio_ci.hi < 1;
    EXPECT_EQ(excludes_one, r.p_value() < 0.05) << "Fieller excludes 1 exactly when the paired t-test rejects";
    EXPECT_EQ(r.verdict == Verdict::significantly_above, r.ratio_ci.lo > 1);
    above += r.verdict == Verdict::significantly_above;
  }
  EXPECT_GT(above, 100) << "a 3 % gain at rho 0.7 and 12 pairs is found most of the time";
}

TEST(PairedRatio, EdgeCases) {
  EXPECT_THROW(compare_ratio_paired({1, 2}, {1}), std::invalid_argument);
  EXPECT_EQ(compare_ratio_paired({1}, {2}).verdict, Verdict::insufficient_data);
  EXPECT_TRUE(std::isnan(paired_variance_factor({1}, {2})));
  // A baseline mean indistinguishable from 0: Fieller's set is unbounded, reported as no interval.
  const RatioComparison r = compare_ratio_paired({1, 2, 3}, {-1, 1.5, -0.4});
  EXPECT_FALSE(r.ratio_ci.valid());
}

namespace {

PointStatistics point_with(const std::vector<int>& replicates, const std::vector<double>& j) {
  PointStatistics p;
  for (std::size_t i = 0; i < j.size(); ++i) {
    p.j_paper_values.push_back(j[i]);
    p.j_paper_keys.push_back({7, replicates[i]});
  }
  return p;
}

}  // namespace

TEST(PairedRatio, BaselineComparisonPairsOnlyExactReplicateSets) {
  const PointStatistics base = point_with({0, 1, 2, 3}, {10, 11, 9, 10.5});
  const PointStatistics same = point_with({3, 2, 1, 0}, {11.1, 9.4, 11.6, 10.4});  // order does not matter
  EXPECT_FALSE(compare_to_baseline(same, base, JKind::paper).paired) << "unpaired unless asked";
  const RatioComparison paired = compare_to_baseline(same, base, JKind::paper, {}, Pairing::when_exact);
  EXPECT_TRUE(paired.paired);
  EXPECT_EQ(paired.n_a, 4u);
  EXPECT_GT(paired.correlation, 0.9) << "pairs are matched by replicate, not by position";
  EXPECT_FALSE(compare_to_baseline(same, base, JKind::paper, {}, Pairing::never).paired);

  // Replicate 3 has no J at the point, replicate 4 none at the baseline: unpaired, all runs.
  const PointStatistics other = point_with({0, 1, 2, 4}, {10.4, 11.6, 9.4, 12});
  const RatioComparison fallback = compare_to_baseline(other, base, JKind::paper, {}, Pairing::when_exact);
  EXPECT_FALSE(fallback.paired);
  EXPECT_EQ(fallback.n_a, 4u);
  const PairedValues common = pair_by_replicate(other, base, JKind::paper);
  EXPECT_EQ(common.a.size(), 3u);
  EXPECT_EQ(common.only_a, 1u);
  EXPECT_EQ(common.only_b, 1u);
  EXPECT_FALSE(common.exact());
  EXPECT_EQ(common.a, (std::vector<double>{10.4, 11.6, 9.4}));
  EXPECT_EQ(common.b, (std::vector<double>{10, 11, 9}));
  // Another seed is another particle set: no pair.
  PointStatistics reseeded = same;
  for (ReplicateKey& k : reseeded.j_paper_keys) k.first = 8;
  EXPECT_TRUE(pair_by_replicate(reseeded, base, JKind::paper).a.empty());
  EXPECT_FALSE(compare_to_baseline(reseeded, base, JKind::paper, {}, Pairing::when_exact).paired);
}

TEST(PairedRatio, ReportPairingKeyIsReadStrictly) {
  EXPECT_EQ(parse_study_info("[report]\nbaseline = \"none\"\n", "s.toml").report.pairing, Pairing::never);
  EXPECT_EQ(parse_study_info("[report]\npairing = \"paired\"\n", "s.toml").report.pairing, Pairing::when_exact);
  try {
    parse_study_info("[report]\nj = \"paper\"\npairing = \"maybe\"\n", "s.toml");
    ADD_FAILURE() << "no error";
  } catch (const ScenarioError& e) {
    EXPECT_EQ(e.where().line, 3) << e.what();
    EXPECT_NE(std::string(e.what()).find("paired"), std::string::npos) << e.what();
  }
  // The study loader knows the key too (one schema, two readers).
  const std::string study = "[study]\nname = \"t\"\n[[series]]\nlabel = \"a\"\nscenario = \"x.toml\"\n[report]\n";
  EXPECT_EQ(parse_study(study + "pairing = \"paired\"\n", "t.toml", ".").report.pairing, "paired");
  try {
    parse_study(study + "pairing = 1\n", "t.toml", ".");
    ADD_FAILURE() << "no error";
  } catch (const ScenarioError& e) {
    EXPECT_EQ(e.where().line, 7) << e.what();
    EXPECT_EQ(e.key(), "report.pairing");
  }
}

TEST(PairedRatio, ReportPairingCommandPrintsTheTableAndWritesNothing) {
  namespace fs = std::filesystem;
  const fs::path store = gapflow::testing::source_path("results/cylinder-peak-3d");
  const auto before = fs::last_write_time(store / "points.csv");
  const auto r = gapflow::testing::run_gapflow("report " + gapflow::testing::shell_quoted(store.string()) + " --pairing");
  EXPECT_EQ(r.code, 0) << r.output;
  EXPECT_NE(r.output.find("paired by replicate against unpaired"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("median rho"), std::string::npos) << r.output;
  EXPECT_EQ(fs::last_write_time(store / "points.csv"), before);
  // A study file that does not describe the store (here: no runs of study "tiny"): exit 2.
  const auto none = gapflow::testing::run_gapflow("report " + gapflow::testing::shell_quoted(store.string()) +
                                                  " --study " +
                                                  gapflow::testing::shell_quoted(gapflow::testing::source_path(
                                                      "studies/examples/tiny.toml").string()) + " --pairing");
  EXPECT_EQ(none.code, 2) << none.output;
}

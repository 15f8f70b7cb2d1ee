// The model's noise on the response surface, on nodes whose replicates are independent, share part
// of their error, or all of it: the replicates' correlation between nodes as the surface counts it
// (calibrate/node_correlation.hpp), the variance the surface states against the one it has, and the
// surface noise check (calibrate/surface_noise.hpp).
#include "calibrate/data_file.hpp"
#include "calibrate/fit.hpp"
#include "calibrate/node_correlation.hpp"
#include "calibrate/surface_noise.hpp"
#include "common/statistics.hpp"
#include "test_support.hpp"

#include <gtest/gtest.h>
#include <fmt/format.h>

#include <cmath>
#include <iostream>
#include <random>

namespace gapflow {
namespace {

using testing::source_path;

// Standard normal draws by Box-Muller on mt19937_64's bits (std::normal_distribution's algorithm is
// the library's own, so its draws differ between standard libraries).
class Normal {
 public:
  explicit Normal(std::uint64_t seed) : bits_(seed) {}
  double operator()() {
    const double u1 = (static_cast<double>(bits_() >> 11) + 0.5) * 0x1.0p-53, u2 = static_cast<double>(bits_() >> 11) * 0x1.0p-53;
    return std::sqrt(-2 * std::log(u1)) * std::cos(2 * M_PI * u2);
  }

 private:
  std::mt19937_64 bits_;
};

// Nine grid nodes of design v3's free parameter (0.1..0.5); replicate r of point i at node k is a
// smooth response + shared * e[i][r] (the same at every node) + own * e[i][k][r], the last times
// (f / 0.3)^own_power at friction f (0: the same noise at every node). With decay < 1 the shared
// error is a stationary AR(1) from node to node instead, decay^m its correlation m nodes apart (as
// the first crossing's falls off, calibrate/node_correlation.hpp). The surface is built around
// node `centre`, the fit at `fit`.
BaselineFit nodes_with(const DataFile& design, double shared, double own, std::uint64_t seed, int centre = 4,
                       double fit = 0.3, double own_power = 0, double decay = 1) {
  Normal normal(seed);
  const std::size_t n = static_cast<std::size_t>(design.model_replicates), points = design.points.size();
  std::vector<std::vector<double>> common(points, std::vector<double>(n));
  for (auto& row : common)
    for (double& e : row) e = normal();
  BaselineFit base;
  for (int k = 0; k < 9; ++k) {
    if (k > 0 && decay < 1)
      for (auto& row : common)
        for (double& e : row) e = decay * e + std::sqrt(1 - decay * decay) * normal();
    const double f = 0.1 + 0.05 * k;
    base.grid.push_back(ParameterSet{}.with(design.free.front().key, f));
    Prediction p;
    for (std::size_t i = 0; i < points; ++i) {
      std::vector<double> reps;
      for (std::size_t r = 0; r < n; ++r)
        reps.push_back(1.0 + 0.1 * static_cast<double>(i) + 2.0 * f - 3.0 * f * f + shared * common[i][r] +
                       own * std::pow(f / 0.3, own_power) * normal());
      double mean = 0, var = 0;
      for (double v : reps) mean += v / static_cast<double>(n);
      for (double v : reps) var += (v - mean) * (v - mean) / static_cast<double>(n - 1);
      p.fit.push_back(mean), p.value.push_back(mean), p.se_fit.push_back(std::sqrt(var / static_cast<double>(n)));
      p.valid.push_back(true);
      p.replicate_fit.push_back(reps);
    }
    base.grid_predictions.push_back(p);
  }
  base.surface_at = base.grid[static_cast<std::size_t>(centre)];
  base.params = ParameterSet{}.with(design.free.front().key, fit);
  base.surface = surface_around(design, base, base.surface_at);
  return base;
}

DataFile design_v3() { return load_data_file(source_path("data/blind/design_v3.toml")); }

TEST(SurfaceNoise, IndependentNodesGiveNoCorrelationAndNoUnderstatement) {
  const DataFile design = design_v3();
  ASSERT_EQ(design.model_replicates, 12);
  for (std::uint64_t seed = 1; seed <= 5; ++seed) {
    const SurfaceNoiseCheck c = surface_noise_check(design, nodes_with(design, 0.0, 0.05, seed));
    ASSERT_TRUE(c.problem.empty()) << c.problem;
    EXPECT_EQ(c.nodes, 5);
    EXPECT_GT(c.all.points, 30);
    // rho's noise over ~45 points of 11 degrees of freedom each: se about 0.06.
    EXPECT_NEAR(c.all.correlation, 0.0, 0.2) << "seed " << seed;
    EXPECT_NEAR(c.all.understated, 1.0, 0.2) << "seed " << seed;
  }
}

TEST(SurfaceNoise, AnErrorEveryNodeSharesIsFoundWholeAndUnderstatedByOneOverTheLeverage) {
  const DataFile design = design_v3();
  const SurfaceNoiseCheck c = surface_noise_check(design, nodes_with(design, 0.05, 0.0005, 2));
  EXPECT_NEAR(c.all.correlation, 1.0, 0.05);
  EXPECT_NEAR(c.all.understated, 35.0 / 17.0, 0.1);  // the fit on the middle node of five
  // The same data with the fit on the window's end node: there a shared error is nearly all counted.
  const SurfaceNoiseCheck end = surface_noise_check(design, nodes_with(design, 0.05, 0.0005, 2, 4, 0.4));
  EXPECT_NEAR(end.all.correlation, 1.0, 0.05);
  EXPECT_NEAR(end.all.understated, 35.0 / 31.0, 0.05);
  // The surface counts it (calibrate/node_correlation.hpp): the factor it states over independent
  // nodes' is the one the check finds, and the text has nothing to warn of.
  EXPECT_NEAR(c.all.counted, c.all.understated, 0.1);
  EXPECT_NEAR(end.all.counted, end.all.understated, 0.05);
  EXPECT_NE(surface_noise_text(c).find("the surface counts"), std::string::npos) << surface_noise_text(c);
  EXPECT_EQ(surface_noise_text(c).find("Above"), std::string::npos);
}

TEST(NodeCorrelation, PooledOverAnObservablesPointsItFallsOffWithTheNodesDistanceAsTheRunsDo) {
  const DataFile design = design_v3();
  const BaselineFit base = nodes_with(design, 0.05, 0.05, 21, 4, 0.3, 0, 0.8);  // 0.5 x 0.8^m, m nodes apart
  const NodeCorrelations c = node_correlations(design, base.grid, base.grid_predictions);
  ASSERT_EQ(c.of_point.size(), design.points.size());
  for (const ObservableCorrelation& o : c.observables) {
    ASSERT_GT(o.points, 10) << to_string(o.observable);
    EXPECT_NEAR(o.matrix.diagonal().minCoeff(), 1.0, 1e-12);
    EXPECT_NEAR(o.matrix.diagonal().maxCoeff(), 1.0, 1e-12);
    EXPECT_GT(Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(o.matrix).eigenvalues().minCoeff(), -1e-12);  // a Gram matrix
    // From 14 points of 12 replicates each: a correlation's se about 0.07.
    EXPECT_NEAR(o.neighbours, 0.4, 0.15) << to_string(o.observable);
    EXPECT_NEAR(o.matrix(0, 4), 0.2, 0.2) << to_string(o.observable);
    EXPECT_NEAR(o.matrix(0, 8), 0.08, 0.2) << to_string(o.observable);
    EXPECT_GT(o.neighbours - o.matrix(0, 8), 0.15) << to_string(o.observable);  // it falls off: not one constant
  }
  EXPECT_NE(node_correlation_text(c).find("points)"), std::string::npos);
}

TEST(NodeCorrelation, APointLackingAReplicateIsLeftOutAndNodesWithoutReplicatesAreIndependent) {
  const DataFile design = design_v3();
  BaselineFit base = nodes_with(design, 0.05, 0.05, 22);
  const NodeCorrelations before = node_correlations(design, base.grid, base.grid_predictions);
  base.grid_predictions[3].replicate_fit[0][2] = std::nan("");
  const NodeCorrelations after = node_correlations(design, base.grid, base.grid_predictions);
  const std::size_t o = after.of_point[0];
  EXPECT_EQ(after.observables[o].points, before.observables[o].points - 1);
  EXPECT_GT(after.observables[o].neighbours, 0.3);  // a shared error: 0.5 between any two nodes
  for (Prediction& p : base.grid_predictions) p.replicate_fit.assign(design.points.size(), {});
  const NodeCorrelations none = node_correlations(design, base.grid, base.grid_predictions);
  for (const ObservableCorrelation& c : none.observables) {
    EXPECT_EQ(c.points, 0);
    EXPECT_TRUE(c.matrix.isIdentity());
  }
  EXPECT_NE(node_correlation_text(none).find("none"), std::string::npos);
  // One node (a data file without free parameters): no pair to correlate, and the log says so.
  const BaselineFit again = nodes_with(design, 0.05, 0.05, 22);
  const NodeCorrelations one = node_correlations(design, {again.grid[0]}, {again.grid_predictions[0]});
  EXPECT_TRUE(one.observables.front().matrix.isIdentity());
  EXPECT_NE(node_correlation_text(one).find("n/a (one node)"), std::string::npos) << node_correlation_text(one);
}

TEST(SurfaceNoise, IndependentNodesAreCountedAsIndependent) {
  const DataFile design = design_v3();
  double counted = 0;
  for (std::uint64_t seed = 1; seed <= 5; ++seed) counted += surface_noise_check(design, nodes_with(design, 0.0, 0.05, seed)).all.counted / 5;
  EXPECT_NEAR(counted, 1.0, 0.1);  // the pooled correlations' noise, about 0.03 each, sums over 5 x 5 nodes
}

TEST(SurfaceNoise, HalfTheVarianceSharedGivesACorrelationOfAHalf) {
  const DataFile design = design_v3();
  double sum = 0;
  for (std::uint64_t seed = 11; seed <= 14; ++seed)
    sum += surface_noise_check(design, nodes_with(design, 0.03, 0.03, seed)).all.correlation;
  EXPECT_NEAR(sum / 4, 0.5, 0.12);
}

TEST(SurfaceNoise, OnlyTheWindowsNodesCountAndIncompletePointsAreLeftOut) {
  const DataFile design = design_v3();
  BaselineFit base = nodes_with(design, 0.0, 0.05, 3);
  const int all = surface_noise_check(design, base).all.points;
  std::size_t fitted = 0;
  while (design.points[fitted].held_out) ++fitted;
  base.grid_predictions[0].replicate_fit[fitted][5] = std::nan("");  // node 0.1: outside the window 0.2-0.4
  EXPECT_EQ(surface_noise_check(design, base).all.points, all);
  base.grid_predictions[2].replicate_fit[fitted][5] = std::nan("");  // node 0.2: inside
  EXPECT_EQ(surface_noise_check(design, base).all.points, all - 1);
}

// A first effect's shifts are its runs less the baseline's own runs at the grid nodes nearest the
// fit, the runs the surface's quadratic goes through (effect_responses.cpp); the prediction's se
// counts what the two share (Surface::predict_fit). Monte Carlo over `draws` independent sets of
// nodes (own noise only) and moved runs correlated `rho` with their partners (common random numbers),
// the effect at its one measured size: the variance of the prediction over the draws, and the
// stated one (mean se^2), each the mean over the points.
struct PredictionVariance {
  double observed = 0, stated = 0;
};
// Each point's prediction over the draws: its variance, and the mean of the variance it states.
class PointMoments {
 public:
  explicit PointMoments(std::size_t points) : sum_(points, 0.0), sum2_(points, 0.0), stated_(points, 0.0) {}
  void add(const Prediction& p) {
    for (std::size_t i = 0; i < sum_.size(); ++i)
      sum_[i] += p.fit[i], sum2_[i] += p.fit[i] * p.fit[i], stated_[i] += p.se_fit[i] * p.se_fit[i];
    ++draws_;
  }
  PredictionVariance result() const {  // each the mean over the points
    PredictionVariance out;
    const double n = draws_, points = static_cast<double>(sum_.size());
    for (std::size_t i = 0; i < sum_.size(); ++i) {
      out.observed += (sum2_[i] - sum_[i] * sum_[i] / n) / (n - 1) / points;
      out.stated += stated_[i] / n / points;
    }
    return out;
  }

 private:
  std::vector<double> sum_, sum2_, stated_;
  int draws_ = 0;
};
// `moved_scale`: the moved runs' noise over their partners' (an effect that changes the noise);
// `partners`: the term given its pairs and their partners (EffectTerm::partners), so that it counts
// the partner share and the sizes' correlation; else a one-size term as a signature makes (-1/2).
PredictionVariance prediction_variance(const DataFile& design, double rho, bool paired, int draws,
                                       double moved_scale = 1, bool partners = false) {
  const double own = 0.05, shift = 0.2;
  const std::size_t points = design.points.size(), reps = static_cast<std::size_t>(design.model_replicates);
  PointMoments moments(points);
  for (int d = 0; d < draws; ++d) {
    BaselineFit base = nodes_with(design, 0.0, own, 100 + static_cast<std::uint64_t>(d));
    // The nodes' se's set to their truth, so that the stated variance carries no estimate's noise
    // but the shift's (the quadratic's own is checked by the next test).
    for (Prediction& node : base.grid_predictions) node.se_fit.assign(points, own / std::sqrt(static_cast<double>(reps)));
    base.surface = surface_around(design, base, base.surface_at);
    Normal normal(5000 + static_cast<std::uint64_t>(d));
    std::vector<double> mean, se;
    std::vector<std::vector<double>> pairs(points), partner(points);
    std::vector<ParameterSet> near;
    for (std::size_t k : nearest_nodes(base.grid, base.surface, base.params)) near.push_back(base.grid[k]);
    for (std::size_t i = 0; i < points; ++i) {
      for (std::size_t k : nearest_nodes(base.grid, base.surface, base.params)) {
        const double f = base.grid[k].get(design.free.front().key, 0);
        const double truth = 1.0 + 0.1 * static_cast<double>(i) + 2.0 * f - 3.0 * f * f;
        const std::vector<double>& runs = base.grid_predictions[k].replicate_fit[i];
        for (std::size_t r = 0; r < reps; ++r) {
          const double b = runs[r];
          const double m = truth + shift + moved_scale * (rho * (b - truth) + std::sqrt(1 - rho * rho) * own * normal());
          pairs[i].push_back(m - b), partner[i].push_back(b);
        }
      }
      const Summary s = summarize(pairs[i]);
      mean.push_back(s.mean), se.push_back(s.se());
    }
    EffectTerm term = EffectTerm::single_step("e", "k", 0.0, 0.0, 1.0, 1.0, mean, se);
    if (partners) {
      term.partners = partner;
      term.paired_with = near;  // before the size is added: the pairs run node by node over these
      term.add_size(1.0, mean, se, pairs);
    }
    if (paired) term.paired_with = near;
    base.surface.effects.push_back(term);
    const Prediction p = base.surface.predict_fit(base.params.with("k", 1.0));
    moments.add(p);
  }
  return moments.result();
}

// The quadratic alone, its nodes' se's estimated from their own runs (6 a node, as blind designs
// v2 and v3's twins calibrate with): the variance of its value at the fit over independent draws
// of the nodes, against the mean variance it states, each the mean over the points.
// `shared` and `decay` as in nodes_with; `independent` (optional) gets the variance independent nodes
// would state, the mean over the draws and points.
PredictionVariance quadratic_variance(const DataFile& design, int draws, double fit = 0.3, double own_power = 0,
                                      double shared = 0, double decay = 1, double* independent = nullptr) {
  const std::size_t points = design.points.size();
  PointMoments moments(points);
  double sum = 0;
  for (int d = 0; d < draws; ++d) {
    const BaselineFit base =
        nodes_with(design, shared, 0.05, 300 + static_cast<std::uint64_t>(d), 4, fit, own_power, decay);
    const Prediction p = base.surface.predict_fit(base.params);
    moments.add(p);
    for (std::size_t i = 0; i < points; ++i) sum += base.surface.independent_nodes_variance(base.params, i);
  }
  if (independent) *independent = sum / draws / static_cast<double>(points);
  return moments.result();
}

TEST(SurfaceNoise, TheQuadraticStatesItsOwnVarianceWhenEachNodesSeComesFromSixRunsEvenWhereTheNoiseVaries) {
  const DataFile design = load_data_file(source_path("data/blind/design_v2.toml"));
  ASSERT_EQ(design.model_replicates, 6);
  // In units of one node's mean's variance (0.05^2/6): weighted by each node's own se (until
  // af66c1c), observed 0.585 and stated 0.498; every node alike (fit.cpp, regress_point), observed
  // 0.481 (the equal weights' 0.486) and stated 0.562 (0.547 with the lack of fit read against the
  // nodes' mean variance and scaling the covariance, until c98ba56). Stated above observed by the
  // lack-of-fit widening: the nodes' reduced chi^2 is read against variances estimated from few
  // runs, which biases it above 1 (about 25/23 for five nodes of 6), and its excess is added wherever
  // it exceeds 1.
  const PredictionVariance q = quadratic_variance(design, 300);
  EXPECT_GT(q.stated / q.observed, 0.95);
  EXPECT_LT(q.stated / q.observed, 1.2);
  // The noise growing with the friction, its variance 0.20 to 3.2 times the middle node's over the
  // window, and the fit at the window's noisiest end, where that node's weight is 31/35: observed
  // 2.69, stated 2.82. One variance pooled over the nodes (af66c1c) would state about 1.2 there.
  const PredictionVariance end = quadratic_variance(design, 300, 0.4, 2.0);
  EXPECT_GT(end.stated / end.observed, 0.95);
  EXPECT_LT(end.stated / end.observed, 1.2);
}

TEST(SurfaceNoise, TheQuadraticCountsTheErrorItsNodesShareWhetherAlikeBetweenAnyTwoOrFallingOffWithDistance) {
  const DataFile design = load_data_file(source_path("data/blind/design_v2.toml"));
  // Half the variance shared by every node (rho = 0.5 between any two), then an AR(1) from node to
  // node with 0.8 per step and the same share (rho 0.4 between neighbours, 0.2 four apart). The fit on
  // the window's middle node, where independent nodes would pass 17/35 of a node's variance and a
  // shared error passes whole. In units of a node's variance, exact 0.743 and 0.700; measured (300
  // draws) 0.742 and 0.711, stated 0.739 and 0.696 (with the lack of fit's excess scaling the whole
  // covariance, shared part included, 0.786 and 0.728); as independent nodes, 0.486 both.
  for (const double decay : {1.0, 0.8}) {
    double independent = 0;
    const PredictionVariance q = quadratic_variance(design, 300, 0.3, 0, 0.05, decay, &independent);
    EXPECT_GT(q.stated / q.observed, 0.9) << "decay " << decay;
    EXPECT_LT(q.stated / q.observed, 1.15) << "decay " << decay;
    EXPECT_LT(independent / q.observed, 0.85) << "decay " << decay;  // what was stated before: the test can fail
  }
}

TEST(SurfaceNoise, AFirstEffectsShiftsPairedWithTheSurfacesOwnRunsShareTheirNoiseWithIt) {
  const DataFile design = design_v3();
  // sigma^2 = one node's mean's variance; the fit on the window's middle node (quadratic weights
  // (-3, 12, 17, 12, -3)/35), the shift over its 3 nearest nodes. The prediction's variance is
  // 0.371 sigma^2 at rho = 0 and 0.428 at 0.5; counted as independent, the quadratic's 0.486 and
  // the shift's 2 (1 - rho)/3 add up to 1.15 and 0.82 (calibrate/README.md). Measured here:
  // observed 0.371 and 0.424, stated 0.399 and 0.456 (without the shared part 1.178 and 0.843); the
  // stated exceed the exact ones by the lack-of-fit widening, which adds the excess of the nodes'
  // pooled reduced chi^2 wherever that exceeds 1 by chance.
  for (const double rho : {0.0, 0.5}) {
    const PredictionVariance with = prediction_variance(design, rho, true, 200);
    EXPECT_NEAR(with.stated / with.observed, 1.0, 0.1) << "rho " << rho;
    const PredictionVariance without = prediction_variance(design, rho, false, 200);
    EXPECT_GT(without.stated / without.observed, 1.6) << "rho " << rho;
    EXPECT_NEAR(without.observed, with.observed, 1e-12);  // the same draws
  }
}

TEST(SurfaceNoise, AnEffectThatChangesTheNoiseHasItsPartnerShareReadOffThePairs) {
  const DataFile design = design_v3();
  // Moved runs with 0.7, 1 and 1.5 times their partners' noise, keeping 0 or 0.5 of it. With the
  // partner share at -1/2 (every pass up to 25) the stated variance is 2.13 and 1.96 times the
  // observed at 0.7, 1.08 and 1.07 at 1, 0.43 and 0.48 at 1.5: the covariance of the shift with the nodes'
  // runs is -Var(b)/N for rho 0, not -Var(d)/2N, and at the window's middle node, where the paired
  // nodes hold nearly all of the quadratic's weight, the stated variance hardly moves with the moved
  // runs' noise. Read off the partners: 1.15, 1.12, 1.08, 1.07, 1.04, 1.04 (the stated exceed the
  // exact ones by the lack-of-fit widening, as above, the more the smaller the prediction's own
  // variance, at 0.7).
  for (const double scale : {0.7, 1.0, 1.5})
    for (const double rho : {0.0, 0.5}) {
      const PredictionVariance counted = prediction_variance(design, rho, true, 200, scale, true);
      const PredictionVariance half = prediction_variance(design, rho, true, 200, scale, false);
      std::cout << fmt::format("moved noise x{} rho {}: stated / observed {:.2f} (partner share -1/2: {:.2f})\n", scale,
                               rho, counted.stated / counted.observed, half.stated / half.observed);
      EXPECT_GT(counted.stated / counted.observed, 0.9) << scale << " " << rho;
      EXPECT_LT(counted.stated / counted.observed, 1.25) << scale << " " << rho;
      EXPECT_NEAR(counted.observed, half.observed, 1e-12);  // the same draws
      if (scale == 1.5) {
        EXPECT_LT(half.stated / half.observed, 0.6);  // what was stated: the test can fail
      }
    }
}

TEST(SurfaceNoise, ATermPairedWithNodesOutsideTheSurfaceAddsItsVarianceAsIndependent) {
  const DataFile design = design_v3();
  BaselineFit base = nodes_with(design, 0.0, 0.05, 7);
  const std::size_t points = design.points.size();
  EffectTerm term = EffectTerm::single_step("e", "k", 0.0, 0.0, 1.0, 1.0, std::vector<double>(points, 0.2),
                                            std::vector<double>(points, 0.03));
  Surface alone = base.surface;
  alone.effects.push_back(term);
  term.paired_with = {base.grid[0], base.grid[8]};  // 0.1 and 0.5: outside the window 0.2-0.4
  Surface outside = base.surface;
  outside.effects.push_back(term);
  const ParameterSet at = base.params.with("k", 0.6);
  EXPECT_EQ(outside.predict_fit(at).se_fit, alone.predict_fit(at).se_fit);
  term.paired_with = {base.grid[4]};  // 0.3: inside
  Surface inside = base.surface;
  inside.effects.push_back(term);
  std::size_t fitted = 0;
  while (design.points[fitted].held_out) ++fitted;
  EXPECT_LT(inside.predict_fit(at).se_fit[fitted], alone.predict_fit(at).se_fit[fitted]);
}

// The count of covariances held at their Cauchy-Schwarz bound (summary.json shared_covariance_at_bound). A
// one-size term (shift se s a unit of size) paired with two of the window's nodes states, at a size a from
// neutral, a shift variance (a s)^2 and a covariance with the quadratic of -(c1 + c2) a s^2/2 (c: the
// quadratic's weights on the two nodes, 12/35 and 17/35 at the middle node); the bound is
// sqrt(c1^2 v1 + c2^2 v2) a s (v: the nodes' variances). With s = 0.01 and the nodes' se about 0.014 it
// holds; with their variances made tiny it binds at every point. The count reads the same parts the
// prediction adds (fit.cpp effect_part), so it describes the stated se's own covariances.
TEST(SurfaceNoise, TheCovariancesHeldAtTheirBoundAreCounted) {
  const DataFile design = design_v3();
  BaselineFit base = nodes_with(design, 0.0, 0.05, 7);
  const std::size_t points = design.points.size();
  EffectTerm term = EffectTerm::single_step("e", "k", 0.5, 0.5, 1.5, 1.0, std::vector<double>(points, 0.2),
                                            std::vector<double>(points, 0.01));
  const ParameterSet at = base.params.with("k", 1.1);
  Surface outside = base.surface;
  term.paired_with = {base.grid[0]};  // 0.1: not a node of the window 0.2-0.4
  outside.effects.push_back(term);
  EXPECT_EQ(outside.shared_covariance_bound(at).pairs, 0);
  term.paired_with = {base.grid[3], base.grid[4]};  // 0.25 and 0.3 (the window's middle node)
  Surface inside = base.surface;
  inside.effects.push_back(term);
  const SharedCovarianceBound within = inside.shared_covariance_bound(at);
  EXPECT_EQ(within.pairs, static_cast<int>(points));
  EXPECT_EQ(within.at_bound, 0);
  for (const ParameterSet& paired : term.paired_with) {
    std::size_t n = 0;
    while (n < inside.nodes.size() && inside.nodes[n].values != paired.values) ++n;
    ASSERT_LT(n, inside.nodes.size());
    for (std::vector<double>& node : inside.node_variance) node[n] = 1e-12;
  }
  const SharedCovarianceBound held = inside.shared_covariance_bound(at);
  EXPECT_EQ(held.pairs, static_cast<int>(points));
  EXPECT_EQ(held.at_bound, static_cast<int>(points));
  // At neutral the shift has no variance: nothing to covary, nothing counted.
  EXPECT_EQ(inside.shared_covariance_bound(base.params.with("k", 0.5)).pairs, 0);
}

}  // namespace
}  // namespace gapflow

// The surface noise check (calibrate/surface_noise.hpp): the replicates' correlation between grid
// nodes, and how much the surface understates the model's variance at the baseline, on nodes
// whose replicates are independent, share part of their error, or all of it.
#include "calibrate/data_file.hpp"
#include "calibrate/fit.hpp"
#include "calibrate/surface_noise.hpp"
#include "test_support.hpp"

#include <gtest/gtest.h>

#include <cmath>
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
// smooth response + shared * e[i][r] (the same at every node) + own * e[i][k][r]. The surface is
// built around node `centre`, the fit at `fit`.
BaselineFit nodes_with(const DataFile& design, double shared, double own, std::uint64_t seed, int centre = 4,
                       double fit = 0.3) {
  Normal normal(seed);
  const std::size_t n = static_cast<std::size_t>(design.model_replicates), points = design.points.size();
  std::vector<std::vector<double>> common(points, std::vector<double>(n));
  for (auto& row : common)
    for (double& e : row) e = normal();
  BaselineFit base;
  for (int k = 0; k < 9; ++k) {
    const double f = 0.1 + 0.05 * k;
    base.grid.push_back(ParameterSet{}.with(design.free.front().key, f));
    Prediction p;
    for (std::size_t i = 0; i < points; ++i) {
      std::vector<double> reps;
      for (std::size_t r = 0; r < n; ++r)
        reps.push_back(1.0 + 0.1 * static_cast<double>(i) + 2.0 * f - 3.0 * f * f + shared * common[i][r] + own * normal());
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
  EXPECT_NE(surface_noise_text(c).find("understates"), std::string::npos);
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

}  // namespace
}  // namespace gapflow

// The surface noise check (calibrate/surface_noise.hpp): the baseline's model variance from each
// replicate's own surface against what the surface reports, on nodes whose replicates are
// independent and on nodes whose replicates share their error (as common random numbers can make them).
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

// Nine grid nodes of design v3's free parameter (0.1..0.5), each point's replicate r at node k
// = a smooth response + shared * e[r] (the same at every node) + own * e[k][r] (each node its own).
BaselineFit nodes_with(const DataFile& design, double shared, double own, unsigned seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> normal;
  const std::size_t n = static_cast<std::size_t>(design.model_replicates), points = design.points.size();
  std::vector<std::vector<double>> common(points, std::vector<double>(n));
  for (auto& row : common)
    for (double& e : row) e = normal(rng);
  BaselineFit base;
  for (int k = 0; k < 9; ++k) {
    const double f = 0.1 + 0.05 * k;
    base.grid.push_back(ParameterSet{}.with(design.free.front().key, f));
    Prediction p;
    for (std::size_t i = 0; i < points; ++i) {
      std::vector<double> reps;
      for (std::size_t r = 0; r < n; ++r)
        reps.push_back(1.0 + 0.1 * static_cast<double>(i) + 2.0 * f - 3.0 * f * f + shared * common[i][r] +
                       own * normal(rng));
      double mean = 0, var = 0;
      for (double v : reps) mean += v / static_cast<double>(n);
      for (double v : reps) var += (v - mean) * (v - mean) / static_cast<double>(n - 1);
      p.fit.push_back(mean), p.value.push_back(mean), p.se_fit.push_back(std::sqrt(var / static_cast<double>(n)));
      p.valid.push_back(true);
      p.replicate_fit.push_back(reps);
    }
    base.grid_predictions.push_back(p);
  }
  base.surface_at = base.grid[4];  // the middle node, 0.3
  base.params = base.grid[4];
  base.surface = surface_around(design, base, base.surface_at);
  return base;
}

TEST(SurfaceNoise, IndependentNodesGiveAboutOne) {
  const DataFile design = load_data_file(source_path("data/blind/design_v3.toml"));
  ASSERT_EQ(design.model_replicates, 12);
  const SurfaceNoiseCheck c = surface_noise_check(design, nodes_with(design, 0.0, 0.05, 1));
  EXPECT_EQ(c.replicates, 12);
  EXPECT_GT(c.points, 30);
  // Seeds 1 and 4-7 give 0.88-1.01 (below 1 where the lack of fit, itself noisy, widens the
  // reported variance); the median over ~45 points lies within about +-0.15 of 1.
  EXPECT_GT(c.median_ratio, 0.8);
  EXPECT_LT(c.median_ratio, 1.2);
}

TEST(SurfaceNoise, ErrorSharedByEveryNodeIsSeenAsTheLeverageUnderstatesIt) {
  // Fully shared, the prediction at the middle node carries all of it, while the surface reports
  // the leverage's share, 17/35: the ratio is near 35/17 = 2.06 (a little less: the own part averages).
  const DataFile design = load_data_file(source_path("data/blind/design_v3.toml"));
  const SurfaceNoiseCheck c = surface_noise_check(design, nodes_with(design, 0.05, 0.005, 2));
  EXPECT_GT(c.median_ratio, 1.7);
  EXPECT_LT(c.median_ratio, 2.4);
  EXPECT_NE(surface_noise_text(c).find("surface noise check"), std::string::npos);
}

TEST(SurfaceNoise, PointsWithoutEveryReplicateAreLeftOut) {
  const DataFile design = load_data_file(source_path("data/blind/design_v3.toml"));
  BaselineFit base = nodes_with(design, 0.0, 0.05, 3);
  const int all = surface_noise_check(design, base).points;
  base.grid_predictions[2].replicate_fit[0][5] = std::nan("");  // one replicate of point 0 at one node
  EXPECT_EQ(surface_noise_check(design, base).points, all - (design.points[0].held_out ? 0 : 1));
}

}  // namespace
}  // namespace gapflow

// The effect fit on a response surface: its objective and its restart from the profile scan.
#include "calibrate/data_file.hpp"
#include "calibrate/fit.hpp"
#include "test_support.hpp"

#include <gtest/gtest.h>

#include <cmath>

namespace gapflow {
namespace {

using testing::source_path;

// Two points of a linear-scale observable, both measured at 0.95 +- 0.05.
DataFile two_points() {
  const std::string head =
      testing::data_file_head("set = [\"particles.count=30\", \"run.time_limit_s=10\"]\nreplicates = 2\n");
  const std::string points =
      "[[point]]\nW_over_d = 4\nobservable = \"exit_offset\"\nvalue = 0.95\nuncertainty = 0.05\n"
      "[[point]]\nW_over_d = 5\nobservable = \"exit_offset\"\nvalue = 0.95\nuncertainty = 0.05\n";
  return parse_data_file(head + points, "t.toml", source_path(""));
}

// A surface without free parameters, 0 at both points, and one effect of size 0..3
// measured at 0, 1, 2, 3 with the shifts given per size (both points' se `se`).
Surface flat_surface_with(const std::vector<std::vector<double>>& shifts, double se) {
  Surface s;
  for (int i = 0; i < 2; ++i) {
    s.coef.push_back(Eigen::VectorXd::Zero(1));
    s.cov.push_back(Eigen::MatrixXd::Zero(1, 1));
    s.valid.push_back(true);
  }
  EffectTerm t = EffectTerm::single_step("e", "k", 0.0, 0.0, 3.0, 1.0, shifts[0], {se, se});
  t.add_size(2.0, shifts[1], {se, se});
  t.add_size(3.0, shifts[2], {se, se});
  s.effects.push_back(t);
  return s;
}

TEST(EffectFit, RestartsFromTheProfilesBestWhenTheFirstFitStopsAtAKink) {
  // Point 0 responds 0, 1, 0.5, 1 at sizes 0..3, point 1 0, 0.6, 0.5, 1: both reach the data
  // (0.95) only at size 2.9; on the first segment they cannot both, and size 1 is a kink
  // where the deviance has a local minimum (it falls toward 1 from below and rises after it).
  const DataFile data = two_points();
  const Surface s = flat_surface_with({{1.0, 0.6}, {0.5, 0.5}, {1.0, 1.0}}, 0.01);
  const ParameterSet start = ParameterSet{}.with("k", 0.5);
  const double local = fit_surface(data, s, start).get("k", -1);
  EXPECT_NEAR(local, 1.0, 0.05) << "the set-up no longer has the local minimum this test is about";
  const EffectFit fit = fit_effect(data, s, start, 0, 1);
  EXPECT_TRUE(fit.restarted);
  EXPECT_NEAR(fit.params.get("k", -1), 2.9, 0.01);
  EXPECT_LE(fit.interval.lo, fit.params.get("k", -1));
  EXPECT_GE(fit.interval.hi, fit.params.get("k", -1));
  EXPECT_GT(fit.interval.lo, 2.0);  // size 1 is far outside: deviance 50 above the minimum
}

}  // namespace
}  // namespace gapflow

// What a calibration's data could have seen (calibrate/detectability.hpp): the power of the loop's
// two gates against a noncentrality, the smallest detectable departure, and its report line.
#include "calibrate/detectability.hpp"
#include "calibrate/effect_catalogue.hpp"
#include "common/statistics.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace gapflow {
namespace {

TEST(Detectability, OneDegreeOfFreedomPowerIsTheTwoSidedNormalPower) {
  // chi^2_1(lambda) = (Z + sqrt(lambda))^2: power = Phi(-a - b) + 1 - Phi(a - b), a = z_{1-alpha/2}.
  for (double alpha : {0.05, 0.005}) {
    const double a = std::sqrt(chi_square_quantile(1 - alpha, 1));
    for (double lambda : {0.5, 2.0, 7.85, 20.0}) {
      const double b = std::sqrt(lambda);
      EXPECT_NEAR(chi_square_test_power(lambda, 1, alpha), normal_cdf(-a - b) + 1 - normal_cdf(a - b), 1e-9)
          << alpha << " " << lambda;
    }
  }
  EXPECT_NEAR(chi_square_test_power(0, 12, 0.05), 0.05, 1e-12);  // no effect: the level
}

TEST(Detectability, TheSmallestNoncentralityGivesThePowerAskedFor) {
  // One point, one test: the textbook (z_{0.975} + z_{0.8})^2 = 7.85 (up to the far tail).
  EXPECT_NEAR(min_detectable_noncentrality(1, 0.05, 0.05, 0.8), std::pow(1.959964 + 0.841621, 2), 0.01);
  // With many points the residual's chi^2 gate binds: more lambda, and exactly the power there.
  const double lambda = min_detectable_noncentrality(30, 0.05, 0.05 / 8, 0.8);
  EXPECT_GT(lambda, 12.0);
  const double chi_power = chi_square_test_power(lambda, 30, 0.05), score_power = chi_square_test_power(lambda, 1, 0.05 / 8);
  EXPECT_NEAR(std::min(chi_power, score_power), 0.8, 1e-6);
  EXPECT_GE(std::max(chi_power, score_power), 0.8 - 1e-9);
}

TEST(Detectability, SimulatedResidualsAtTheSmallestDepartureAreDetectedAtThatRate) {
  // Whitened residuals a u~ + N(0, I) over 20 points, u~ a unit-norm direction, at lambda*: the
  // binding gate (the chi^2 over 20 points) passes in 80 % of draws, both together a little less
  // (they are correlated, not identical). 20 000 draws: Monte Carlo se 0.003.
  const int n = 20, draws = 20000;
  const double alpha = 0.05, score_alpha = 0.05 / 6;
  const double lambda = min_detectable_noncentrality(n, alpha, score_alpha, 0.8);
  const double chi_critical = chi_square_quantile(1 - alpha, n), score_critical = chi_square_quantile(1 - score_alpha, 1);
  std::mt19937_64 rng(42);
  std::normal_distribution<double> z;
  int chi_passed = 0, both = 0;
  for (int d = 0; d < draws; ++d) {
    double chi2 = 0, along = 0;
    for (int i = 0; i < n; ++i) {
      const double r = (i == 0 ? std::sqrt(lambda) : 0.0) + z(rng);  // u~ = e_1
      chi2 += r * r;
      if (i == 0) along = r;
    }
    chi_passed += chi2 > chi_critical ? 1 : 0;
    both += chi2 > chi_critical && along * along > score_critical ? 1 : 0;
  }
  EXPECT_NEAR(static_cast<double>(chi_passed) / draws, 0.8, 0.012);
  const double joint = static_cast<double>(both) / draws;
  EXPECT_GT(joint, 0.77);
  EXPECT_LE(joint, 0.805);
}

TEST(Detectability, TheFTestsPowerIsTheChiSquaresWithAWellKnownScaleAndLessWithoutOne) {
  // F(d1, d2) with d2 large is chi^2(d1) / d1: the same power. With few rest degrees of freedom the
  // scale is uncertain and the power is lower at the same lambda; at lambda 0 it is the level.
  EXPECT_NEAR(f_test_power(9.0, 2, 1e7, 0.05), chi_square_test_power(9.0, 2, 0.05), 1e-4);
  EXPECT_LT(f_test_power(9.0, 2, 5, 0.05), chi_square_test_power(9.0, 2, 0.05) - 0.1);
  EXPECT_NEAR(f_test_power(0, 3, 7, 0.01), 0.01, 1e-12);
  // Monte Carlo: noncentral chi^2(2, lambda) over chi^2(6)/6, against the central F's 0.95
  // quantile (5.1433), 20000 draws (binomial sd 0.35 %).
  std::mt19937_64 rng(23);
  std::normal_distribution<double> z;
  const double lambda = 10, critical = 5.1433;
  int rejected = 0;
  const int draws = 20000;
  for (int k = 0; k < draws; ++k) {
    const double a = z(rng) + std::sqrt(lambda), b = z(rng);
    double rest = 0;
    for (int j = 0; j < 6; ++j) rest += std::pow(z(rng), 2);
    rejected += (a * a + b * b) / 2 / (rest / 6) > critical;
  }
  EXPECT_NEAR(static_cast<double>(rejected) / draws, f_test_power(lambda, 2, 6, 0.05), 0.012);
  const double star = min_detectable_noncentrality_f(2, 6, 0.05, 0.8);
  EXPECT_NEAR(f_test_power(star, 2, 6, 0.05), 0.8, 1e-6);
  EXPECT_TRUE(std::isinf(min_detectable_noncentrality_f(2, 0, 0.05, 0.8)));
}

TEST(Detectability, NothingIsDetectableWithoutResidualDegreesOfFreedom) {
  // chi_square_of gives p = 1 at dof <= 0: the loop attributes nothing, at any size.
  EXPECT_TRUE(std::isinf(min_detectable_noncentrality(0, 0.05, 0.05, 0.8)));
  EXPECT_TRUE(std::isinf(min_detectable_noncentrality(10, 0.05, 0.05, 1.0)));  // power 1 is never reached
  EXPECT_TRUE(std::isnan(chi_square_test_power(3, 0, 0.05)));
}

Candidate candidate(const std::string& effect, double step, bool visible, double se) {
  const EffectDef* e = find_effect(effect);
  Candidate c;
  c.effect = effect;
  c.key = e->key;
  c.neutral = 0;
  c.step = step;
  c.visible = visible;
  c.visibility_p = visible ? 1e-6 : 0.4;
  c.score.se = se;
  return c;
}

TEST(Detectability, AVisibleEffectGetsItsSmallestDepartureAndAnUnseenOneSaysWhereItWasNotSeen) {
  Round round;
  const double se = 0.002;  // rolling resistance, range 0-0.02
  round.candidates = {candidate("rolling_resistance", 0.01, true, se), candidate("linear_drag", 2, true, 1.0),
                      candidate("restitution", -0.4, false, 0)};
  round.candidates[2].neutral = 0.5;  // 0.5 - 0.4 = 0.1: not the range's end (0)
  round.candidates[2].other_step = -0.5, round.candidates[2].other_visibility_p = 0.3;  // the end: 0.0
  const std::vector<Detectability> d = detectability_at_baseline(round, 25);
  ASSERT_EQ(d.size(), 3u);
  const double lambda = min_detectable_noncentrality(25, 0.05, 0.05 / 2, 0.8);  // two visible candidates
  EXPECT_NEAR(d[0].min_departure, std::sqrt(lambda) * se, 1e-12);
  EXPECT_TRUE(d[0].within_range);  // ~0.009 of 0.02
  EXPECT_NE(detectability_text(d[0]).find("at best from a departure of"), std::string::npos) << detectability_text(d[0]);
  // se 1 /s of drag: inside its range exactly when sqrt(lambda*) /s is (neutral 0, range from 0).
  const EffectDef* drag = find_effect("linear_drag");
  EXPECT_EQ(d[1].within_range, std::sqrt(lambda) <= drag->hi) << detectability_text(d[1]);
  EXPECT_FALSE(d[2].visible);
  EXPECT_DOUBLE_EQ(d[2].largest_step, -0.5);
  EXPECT_TRUE(d[2].step_reached_range_end);
  EXPECT_NE(detectability_text(d[2]).find("not seen even at its lower end"), std::string::npos)
      << detectability_text(d[2]);
  EXPECT_NE(detectability_text(d[2]).find("lower end"), std::string::npos) << detectability_text(d[2]);
  round.candidates[2].other_step = 0;  // only the step (to 0.1) tried
  EXPECT_NE(detectability_text(detectability_at_baseline(round, 25)[2]).find("larger departures untested"),
            std::string::npos);
  // A visible signature the fitted parameters mimic entirely (|P u| = 0, so se stays 0).
  round.candidates[0].score.se = 0;
  const Detectability absorbed = detectability_at_baseline(round, 25)[0];
  EXPECT_TRUE(absorbed.absorbed);
  EXPECT_NE(detectability_text(absorbed).find("apart from the fitted parameters"), std::string::npos);
  // No residual degrees of freedom: no finite bound, and the text says why.
  const Detectability no_dof = detectability_at_baseline(round, 0)[1];
  EXPECT_TRUE(std::isinf(no_dof.min_departure));
  EXPECT_NE(detectability_text(no_dof).find("no residual degrees of freedom"), std::string::npos);
}

}  // namespace
}  // namespace gapflow

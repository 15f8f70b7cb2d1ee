// Is an added effect one size across the design? (calibrate/form_check.hpp): the block score test
// behind it on linear problems with known answers, and the verdict it adds. The loop end to end,
// with an effect of another form than the catalogue's, is in test_calibration_synthetic.cpp.
#include "calibrate/attribution.hpp"
#include "calibrate/detectability.hpp"
#include "calibrate/decisions.hpp"
#include "calibrate/form_check.hpp"
#include "common/random.hpp"
#include "common/statistics.hpp"

#include <boost/math/distributions/non_central_chi_squared.hpp>

#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

namespace gapflow {
namespace {

// A design of 3 inclines x 4 other settings (12 points); the fit moves an offset (a friction
// that shifts every point alike) and one effect whose sensitivity grows with the incline, as a
// drag's does. level(i): the incline's index of point i.
constexpr int kPoints = 12;
int level(int i) { return i / 4; }
Eigen::VectorXd effect_sensitivity() {
  Eigen::VectorXd u(kPoints);
  for (int i = 0; i < kPoints; ++i) u(i) = -(0.6 + 0.45 * level(i)) * (1 + 0.1 * (i % 4));
  return u;
}
Eigen::MatrixXd fitted_directions() {
  Eigen::MatrixXd X(kPoints, 2);
  X.col(0) = Eigen::VectorXd::Constant(kPoints, 1.0);
  X.col(1) = effect_sensitivity();
  return X;
}
// The effect's sensitivity split by incline: one column per level.
Eigen::MatrixXd split_by_incline() {
  const Eigen::VectorXd u = effect_sensitivity();
  Eigen::MatrixXd U = Eigen::MatrixXd::Zero(kPoints, 3);
  for (int i = 0; i < kPoints; ++i) U(i, level(i)) = u(i);
  return U;
}
Eigen::VectorXd unit_noise(RandomStream& rng) {
  Eigen::VectorXd e(kPoints);
  for (int i = 0; i < kPoints; ++i) e(i) = rng.normal();
  return e;
}

TEST(FormCheck, ASplitOfAFittedDirectionHasOneDegreeOfFreedomLessThanItsLevels) {
  // The split's columns sum to the effect's own sensitivity, which the fit moves already.
  RandomStream rng(3);
  const Eigen::MatrixXd X = fitted_directions();
  const BlockScore b = score_block(projector_out(X) * unit_noise(rng), X, split_by_incline());
  EXPECT_EQ(b.dof, 2);
  // Nothing to split: no columns, no test.
  EXPECT_EQ(score_block(unit_noise(rng), X, Eigen::MatrixXd(kPoints, 0)).dof, 0);
  EXPECT_EQ(score_block(unit_noise(rng), X, Eigen::MatrixXd(X.col(1))).dof, 0);
}

TEST(FormCheck, TheBlockScoreHoldsItsLevelOnACorrectModel) {
  // Residuals after a least-squares fit of a correct model: P e. At level 0.05 the test rejects
  // 5 % of 4000 draws (binomial sd 0.34 %).
  RandomStream rng(11);
  const Eigen::MatrixXd X = fitted_directions(), U = split_by_incline(), P = projector_out(X);
  int rejected = 0;
  const int draws = 4000;
  for (int k = 0; k < draws; ++k) rejected += score_block(P * unit_noise(rng), X, U).p < 0.05;
  EXPECT_NEAR(static_cast<double>(rejected) / draws, 0.05, 0.012);
}

TEST(FormCheck, ASizeThatGrowsWithTheInclineIsSeenAsOftenAsTheNoncentralChiSquareSays) {
  // The truth: the effect at size 1 on the shallowest incline, 3 and 6 on the others (as a drag
  // quadratic in the speed, read as a linear one, would be); the fit takes one size and the
  // offset. What the one size leaves, P U s, is the test's noncentrality lambda = |P U s|^2, and
  // the share of draws it rejects at 0.05 is the noncentral chi^2's power (0.93 here; binomial sd
  // over 1000 draws 0.8 %).
  RandomStream rng(5);
  const Eigen::MatrixXd X = fitted_directions(), U = split_by_incline(), P = projector_out(X);
  const Eigen::Vector3d sizes(1.0, 3.0, 6.0);
  const double lambda = (P * U * sizes).squaredNorm();
  const boost::math::non_central_chi_squared law(2, lambda);
  const double power = boost::math::cdf(boost::math::complement(law, chi_square_quantile(0.95, 2)));
  ASSERT_GT(power, 0.5) << "the premise: a mismatch the test should see more often than not (lambda " << lambda << ")";
  int seen = 0;
  const int draws = 1000;
  for (int k = 0; k < draws; ++k) seen += score_block(P * (U * sizes + unit_noise(rng)), X, U).p < 0.05;
  EXPECT_NEAR(static_cast<double>(seen) / draws, power, 0.025) << "lambda " << lambda;
  // One size everywhere: the split finds nothing to explain.
  const BlockScore one = score_block(P * (U * Eigen::Vector3d(2, 2, 2)), X, U);
  EXPECT_LT(one.statistic, 1e-9);
}

std::vector<std::string> incline_labels() {
  std::vector<std::string> labels;
  for (int i = 0; i < kPoints; ++i) labels.push_back(std::to_string(level(i)));
  return labels;
}

TEST(FormCheck, ALevelWithTooFewPointsKeepsASizeOfItsOwnUntested) {
  // Levels of 5, 6 and 1 point: the lone point's part of the effect joins the fitted directions,
  // so two levels are tested, on one degree of freedom (it would be two if the lone point were
  // left in the effect's own column, a level tested in all but name).
  std::vector<std::string> labels(kPoints, "a");
  for (int i = 5; i < 11; ++i) labels[i].assign(1, 'b');  // not = "b": a false -Wrestrict in GCC 12 (bug 105329)
  labels[11] = "c";
  RandomStream rng(9);
  const Eigen::MatrixXd X = fitted_directions();
  const FormCheck c = check_split(projector_out(X) * unit_noise(rng), X, effect_sensitivity(), labels, kPoints);
  EXPECT_EQ(c.levels, 2);
  EXPECT_EQ(c.dof, 1);
  EXPECT_EQ(c.rest_dof, kPoints - 3 - 1);  // the offset, the effect, the lone point's size; the test
  // With every level tested: three levels, two degrees of freedom.
  const FormCheck all = check_split(projector_out(X) * unit_noise(rng), X, effect_sensitivity(), incline_labels(), kPoints);
  EXPECT_EQ(all.levels, 3);
  EXPECT_EQ(all.dof, 2);
}

TEST(FormCheck, TheSplitHoldsItsLevelWhateverTheNoisesCommonScale) {
  // Residuals of a correct model whose noise is twice, exactly, or half what it states. The chi^2 of
  // the split alone rejects far too often at twice; tested against the rest of the residual
  // (Fisher's F on its scale, 8 degrees of freedom left: 12 points - offset - effect - 2 tested) it
  // holds 5 % at every scale.
  RandomStream rng(17);
  const Eigen::MatrixXd X = fitted_directions(), P = projector_out(X);
  const Eigen::VectorXd u = effect_sensitivity();
  const std::vector<std::string> labels = incline_labels();
  int chi2_alone = 0;
  const int draws = 4000;
  for (double sigma : {2.0, 1.0, 0.5}) {
    int rejected = 0;
    for (int k = 0; k < draws; ++k) {
      const Eigen::VectorXd r = P * (sigma * unit_noise(rng));
      if (sigma == 2.0) chi2_alone += score_block(r, X, split_by_incline()).p < 0.05;
      const FormCheck c = check_split(r, X, u, labels, kPoints);
      ASSERT_EQ(c.rest_dof, 8);
      rejected += c.p < 0.05;
    }
    EXPECT_NEAR(static_cast<double>(rejected) / draws, 0.05, 0.012) << "noise " << sigma << " x stated";  // sd 0.34 %
  }
  EXPECT_GT(chi2_alone, 0.3 * draws);
}

TEST(FormCheck, TheRestsDegreesOfFreedomAreTheInformativeRowsLessTheFittedAndTestedDirections) {
  // 12 point rows, one of them without a value (a row of zeros, as fitted_rows gives it), and a
  // measurement of the offset as a row of its own: 11 + 1 informative rows (the count fitted_rows
  // makes; given here), less the offset, the effect and the 2 tested directions, leave 8. The zero
  // row and the measurement row change neither the split's degrees of freedom nor the rank.
  Eigen::MatrixXd X = Eigen::MatrixXd::Zero(kPoints + 1, 2);
  X.topRows(kPoints) = fitted_directions();
  X(kPoints, 0) = 1.0;  // the measurement sees the offset only
  X.row(3).setZero();
  Eigen::VectorXd u = X.col(1);
  RandomStream rng(4);
  Eigen::VectorXd r = Eigen::VectorXd::Zero(kPoints + 1);
  r.head(kPoints) = unit_noise(rng);
  r(kPoints) = rng.normal();
  r(3) = 0;
  const FormCheck c = check_split(projector_out(X) * r, X, u, incline_labels(), kPoints - 1 + 1);
  EXPECT_EQ(c.dof, 2);
  EXPECT_EQ(c.rest_dof, 8);
  // Nothing left beside the test: no test.
  EXPECT_EQ(check_split(projector_out(X) * r, X, u, incline_labels(), 4).dof, 0);
}

// The inclines by value, 5, 8 and 12 degrees: unevenly spaced, and not in string order.
std::vector<std::string> incline_degree_labels() {
  const char* degrees[] = {"5", "8", "12"};
  std::vector<std::string> labels;
  for (int i = 0; i < kPoints; ++i) labels.push_back(degrees[level(i)]);
  return labels;
}

TEST(FormCheck, ASpreadAtTheDetectableSpreadIsFlaggedWithTheStatedPower) {
  // The effect's departure 2 key units at 5 degrees, growing straight with the incline by a
  // fraction `spread` of it up to 12 degrees (3/7 of that at 8); the fit takes one size and the
  // offset, the check tests the split against the rest of the residual (rest dof 8). At the spread
  // the check states it flags with power 0.8, 4000 draws reject at its level 80 % of the time
  // (binomial sd 0.6 %): the noncentral F and the trend's noncentrality (by the levels' values,
  // not their order: 8 lies at 3/7) agree with what the check does.
  const double departure = 2, alpha = 0.05;
  const Eigen::MatrixXd X = fitted_directions(), U = split_by_incline(), P = projector_out(X);
  const Eigen::VectorXd u = effect_sensitivity();
  RandomStream rng(17);
  FormCheck design = check_split(P * unit_noise(rng), X, u, incline_degree_labels(), kPoints);
  ASSERT_EQ(design.dof, 2);
  ASSERT_EQ(design.rest_dof, 8);
  const double spread = detectable_spread(design, departure, alpha, 0.8);
  ASSERT_TRUE(std::isfinite(spread));
  const Eigen::Vector3d sizes = departure * Eigen::Vector3d(1, 1 + spread * 3 / 7, 1 + spread);
  int flagged = 0;
  const int draws = 4000;
  for (int k = 0; k < draws; ++k)
    flagged += check_split(P * (U * sizes + unit_noise(rng)), X, u, incline_degree_labels(), kPoints).p < alpha;
  EXPECT_NEAR(static_cast<double>(flagged) / draws, 0.8, 0.025) << "spread " << spread;
  // Twice the departure, half the spread; a check made at a stricter level needs more.
  EXPECT_NEAR(detectable_spread(design, 2 * departure, alpha, 0.8), spread / 2, 1e-6 * spread);
  EXPECT_GT(detectable_spread(design, departure, alpha / 10, 0.8), spread);
  // The same levels by index (0, 1, 2) put 8 degrees at the middle: another trend, another spread.
  const FormCheck by_index = check_split(P * unit_noise(rng), X, u, incline_labels(), kPoints);
  EXPECT_GT(std::abs(detectable_spread(by_index, departure, alpha, 0.8) / spread - 1), 0.05);
}

TEST(FormCheck, ASpreadIsUnseenWhereTheSizeSitsAtNeutralOrTheLevelsHaveNoOrder) {
  RandomStream rng(19);
  const Eigen::MatrixXd X = fitted_directions();
  const FormCheck c = check_split(projector_out(X) * unit_noise(rng), X, effect_sensitivity(), incline_labels(), kPoints);
  EXPECT_TRUE(std::isinf(detectable_spread(c, 0.0, 0.05, 0.8)));  // no departure to spread
  // Three levels that are not numbers: no trend to test against.
  std::vector<std::string> named(kPoints);
  for (int i = 0; i < kPoints; ++i) named[i] = std::string(1, static_cast<char>('x' + level(i)));
  const FormCheck unordered = check_split(projector_out(X) * unit_noise(rng), X, effect_sensitivity(), named, kPoints);
  ASSERT_EQ(unordered.dof, 2);
  EXPECT_TRUE(std::isnan(detectable_spread(unordered, 1.0, 0.05, 0.8)));
}

TEST(FormCheck, ATrendTheFittedDirectionsTakeInCannotBeSeen) {
  // A fitted direction that is the effect's trend across the inclines (0, 1/2, 1 of it at the three
  // levels): what is left of the trend is rounding, so no spread is detectable, not a huge one.
  Eigen::MatrixXd X = fitted_directions();
  const Eigen::VectorXd u = effect_sensitivity();
  Eigen::VectorXd trend(kPoints);
  for (int i = 0; i < kPoints; ++i) trend(i) = 0.5 * level(i) * u(i);
  X.conservativeResize(Eigen::NoChange, 3);
  X.col(2) = trend;
  RandomStream rng(29);
  const FormCheck c = check_split(projector_out(X) * unit_noise(rng), X, u, incline_labels(), kPoints);
  ASSERT_EQ(c.dof, 1);
  EXPECT_EQ(c.trend_noncentrality, 0.0);
  EXPECT_TRUE(std::isinf(detectable_spread(c, 1.0, 0.05, 0.8)));
}

TEST(FormCheck, ADragOfSpeedExponentNMimicsALinearSizeThatFollowsTheSpeedToTheNMinusOne) {
  // Speeds ~ sqrt(sin theta): a quadratic drag's linear size follows sqrt(sin theta), a linear
  // drag's is one size, a constant force's follows 1 / sqrt(sin theta).
  EXPECT_NEAR(speed_law_size("30", 2), std::sqrt(0.5), 1e-12);
  EXPECT_NEAR(speed_law_size("90", 2), 1.0, 1e-12);
  EXPECT_NEAR(speed_law_size("8", 1), 1.0, 1e-12);
  EXPECT_NEAR(speed_law_size("30", 0), 1 / std::sqrt(0.5), 1e-12);
  EXPECT_NEAR(speed_law_size("12.5", 2) / speed_law_size("5", 2),
              std::sqrt(std::sin(12.5 * M_PI / 180) / std::sin(5 * M_PI / 180)), 1e-12);
  for (const char* bad : {"", "flat", "0", "-5", "95", "8deg"}) EXPECT_TRUE(std::isnan(speed_law_size(bad, 2))) << bad;
}

TEST(FormCheck, ALinearDragsOwnLawAsksNothingAndALevelThatIsNoInclineNoLaw) {
  const Eigen::MatrixXd X = fitted_directions(), P = projector_out(X);
  const Eigen::VectorXd u = effect_sensitivity();
  const LawSize quadratic = [](const std::string& level) { return speed_law_size(level, 2); };
  RandomStream rng(23);
  // A linear drag's own law asks one size everywhere: no spread, nothing for the check to see.
  const FormCheck linear = check_split(P * unit_noise(rng), X, u, incline_degree_labels(), kPoints, {},
                                       [](const std::string& level) { return speed_law_size(level, 1); });
  EXPECT_NEAR(linear.law_spread, 0.0, 1e-12);
  EXPECT_EQ(linear.law_noncentrality, 0.0);
  // A level that is no incline ("0" of the labels 0, 1, 2): no law asked, the check itself made.
  const FormCheck unread = check_split(P * unit_noise(rng), X, u, incline_labels(), kPoints, {}, quadratic);
  EXPECT_EQ(unread.dof, 2);
  EXPECT_TRUE(std::isnan(unread.law_spread));
  EXPECT_TRUE(std::isnan(unread.law_noncentrality));
}

TEST(FormCheck, TheLawsPowerHoldsForDataTheFitReadsAsOneSize) {
  // The whole chain: data made by a quadratic drag's sizes k sqrt(sin theta) at every row (not yet
  // projected), fitted by least squares on the offset and the effect, the fitted departure d read
  // off, and the check on the residual. The law's power at the mean fitted departure is the share of
  // 4000 draws the check flags (binomial sd <= 0.8 %). The effect's sensitivity differs between the
  // levels (0.6, 1.05 and 1.5 per unit), so the fit's one size is a weighted mean of the sizes, not
  // their plain mean: a noncentrality scaled by the plain mean would state another power.
  const double alpha = 0.05;
  const Eigen::MatrixXd X = fitted_directions(), U = split_by_incline();
  const Eigen::VectorXd u = effect_sensitivity();
  const LawSize quadratic = [](const std::string& level) { return speed_law_size(level, 2); };
  const Eigen::Vector3d law(speed_law_size("5", 2), speed_law_size("8", 2), speed_law_size("12", 2));
  RandomStream rng(31);
  const FormCheck design = check_split(projector_out(X) * unit_noise(rng), X, u, incline_degree_labels(), kPoints, {},
                                       quadratic);
  ASSERT_GT(design.law_noncentrality, 0);
  // k such that the check's power is near 0.6 (the fit's one size for k = 1 found by a first fit).
  const auto fit = [&](const Eigen::VectorXd& y) { return Eigen::VectorXd(X.colPivHouseholderQr().solve(y)); };
  const double one_size = fit(U * law)(1);
  const double k = std::sqrt(min_detectable_noncentrality_f(design.dof, design.rest_dof, alpha, 0.6) /
                             design.law_noncentrality) / one_size;
  int flagged = 0;
  double fitted_sum = 0;
  const int draws = 4000;
  for (int n = 0; n < draws; ++n) {
    const Eigen::VectorXd y = U * (k * law) + unit_noise(rng);
    const Eigen::VectorXd b = fit(y);
    fitted_sum += b(1);
    flagged += check_split(y - X * b, X, u, incline_degree_labels(), kPoints).p < alpha;
  }
  const double mean_fitted = fitted_sum / draws;
  const double stated = f_test_power(design.law_noncentrality * mean_fitted * mean_fitted, design.dof, design.rest_dof, alpha);
  EXPECT_NEAR(static_cast<double>(flagged) / draws, stated, 0.025) << "stated " << stated;
  EXPECT_NEAR(stated, 0.6, 0.03);  // the set-up (k was chosen for it); the line above tests the formula
  // The spread the law asks, against the fit's one size.
  EXPECT_NEAR(design.law_spread, (law.maxCoeff() - law.minCoeff()) / one_size, 1e-9);
}

TEST(FormCheck, UntestedLevelsAskingDifferentSizesLeaveTheLawUnasked) {
  // Levels 5, 8 and 12 deg of 4, 4 and 2 points are tested; one-point levels keep a size of their
  // own, untested, in the fitted directions as one column. One such level (20 deg): its part of
  // the law's sizes lies in that column, and the law is asked. Two asking different sizes (3 and
  // 20 deg): Xc holds only their sum, part of the law falls outside the check's directions, and the
  // central F would overstate the power (a second reading measured 0.07 flagged for 0.60 stated):
  // the law is not asked, so it is not established.
  const Eigen::MatrixXd X = fitted_directions(), P = projector_out(X);
  const Eigen::VectorXd u = effect_sensitivity();
  const LawSize quadratic = [](const std::string& level) { return speed_law_size(level, 2); };
  std::vector<std::string> one = incline_degree_labels(), two = incline_degree_labels();
  one[11] = "20";
  two[10] = "3";
  two[11] = "20";
  RandomStream rng(37);
  const FormCheck with_one = check_split(P * unit_noise(rng), X, u, one, kPoints, {}, quadratic);
  const FormCheck with_two = check_split(P * unit_noise(rng), X, u, two, kPoints, {}, quadratic);
  ASSERT_EQ(with_one.levels, 3);
  ASSERT_EQ(with_two.levels, 3);
  EXPECT_TRUE(std::isfinite(with_one.law_noncentrality));
  EXPECT_GT(with_one.law_noncentrality, 0);
  EXPECT_TRUE(std::isnan(with_two.law_noncentrality));
  EXPECT_TRUE(std::isnan(with_two.law_spread));
}

TEST(FormCheck, ADragsLawIsDeterminedOnlyWhereACheckHadThePowerToTellIt) {
  std::vector<FormCheck> checks(3);
  checks[0].effect = "linear_drag";  // along the gap: no law asked
  checks[1].effect = "linear_drag";
  checks[1].law_power = 0.6;
  checks[2].effect = "linear_drag";
  checks[2].law_power = 0.85;
  EXPECT_NEAR(law_power(checks, "linear_drag"), 0.85, 1e-12);
  EXPECT_NEAR(lowest_law_power(checks, {"linear_drag"}), 0.85, 1e-12);
  EXPECT_TRUE(std::isnan(lowest_law_power(checks, {})));  // no drag added: nothing to determine
  EXPECT_TRUE(std::isnan(lowest_law_power(checks, {"size_scatter"})));  // no law in the speed
  // A drag added where no check could ask (the design does not vary the incline): undetermined.
  EXPECT_EQ(lowest_law_power({}, {"linear_drag"}), 0.0);
  // Established: a check with the power, and no check that asked the law flagging it.
  for (FormCheck& c : checks) c.p_adjusted = 0.5;
  EXPECT_TRUE(laws_established(checks, {"linear_drag"}, 0.8, 0.05));
  EXPECT_TRUE(laws_established(checks, {"size_scatter"}, 0.8, 0.05));  // nothing with a law in the speed
  EXPECT_TRUE(laws_established({}, {}, 0.8, 0.05));
  EXPECT_FALSE(laws_established({}, {"linear_drag"}, 0.8, 0.05));     // no check could ask
  checks[1].p_adjusted = 0.01;  // a check that asked the law (power 0.6) flags: not established
  EXPECT_FALSE(laws_established(checks, {"linear_drag"}, 0.8, 0.05));
  checks[1].p_adjusted = 0.5;
  checks[0].p_adjusted = 0.01;  // a flag along another column (no law asked) withholds nothing
  EXPECT_TRUE(laws_established(checks, {"linear_drag"}, 0.8, 0.05));
  checks[2].law_power = 0.5;    // no check with the power
  EXPECT_FALSE(laws_established(checks, {"linear_drag"}, 0.8, 0.05));
  EXPECT_NEAR(lowest_law_power(checks, {"size_scatter", "linear_drag"}), 0.6, 1e-12);
}

TEST(FormCheck, AResidualWhollyInTheSplitIsAMismatchNotNoise) {
  // No noise at all: the residual is the split's own (sizes 1, 3, 6), the rest zero to rounding.
  const Eigen::MatrixXd X = fitted_directions(), U = split_by_incline(), P = projector_out(X);
  const FormCheck c = check_split(P * U * Eigen::Vector3d(1, 3, 6), X, effect_sensitivity(), incline_labels(), kPoints);
  ASSERT_EQ(c.dof, 2);
  EXPECT_GT(c.statistic, 1);
  EXPECT_LT(c.p, 1e-6) << "scale " << c.scale;
}

TEST(FormCheck, WithNoRestTheSplitIsAMismatchUnlessItIsItselfRounding) {
  EXPECT_NEAR(split_p(9.0, 8.0, 2, 8, 17.0), fisher_f_upper(4.5, 2, 8), 1e-12);
  EXPECT_EQ(split_p(9.0, 0.0, 2, 8, 9.0), 0.0);     // the residual all in the split: an infinite F
  EXPECT_EQ(split_p(9.0, -1e-15, 2, 8, 9.0), 0.0);  // the rest below zero by rounding: the same
  EXPECT_EQ(split_p(1e-30, -1e-31, 2, 8, 1.0), 1.0);  // a statistic of rounding: nothing
  EXPECT_EQ(split_p(0.0, 0.0, 2, 8, 0.0), 1.0);     // no residual at all
}

TEST(FormCheck, AnyAdjustedPBelowAlphaFlagsTheForm) {
  std::vector<FormCheck> checks(2);
  checks[0].p_adjusted = 0.2;
  checks[1].p_adjusted = 0.06;
  EXPECT_FALSE(form_differs(checks, 0.05));
  checks[1].p_adjusted = 0.04;
  EXPECT_TRUE(form_differs(checks, 0.05));
  EXPECT_FALSE(form_differs({}, 0.05));
}

TEST(FinalVerdict, ADragWhoseLawTheDesignCannotTellIsSaidAfterTheFailedTests) {
  VerdictEvidence e{.effects_added = 1, .fitted_p_before = 1e-6, .fitted_p_after = 0.4, .held_out_n = 12,
                    .held_out_fresh_p = 0.3, .law_undetermined = true};
  // A poor fit or held-out points beyond the noise are said first (failed tests, not a missing one).
  e.fitted_p_after = 1e-4;
  EXPECT_EQ(final_verdict(e), "effect found, poor fit remains");
  e.fitted_p_after = 0.4;
  e.held_out_fresh_p = 1e-4;
  EXPECT_EQ(final_verdict(e), "effect found; the held-out points are still beyond the noise");
  e.held_out_fresh_p = 0.3;
  EXPECT_EQ(final_verdict(e),
            "effect found; the drag's law in the speed is not established: a drag of another law may be acting");
  e.law_undetermined = false;
  EXPECT_EQ(final_verdict(e), "effect found");
}

}  // namespace
}  // namespace gapflow

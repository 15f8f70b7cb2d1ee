// The calibration loop's decisions on numbers (calibrate/decisions.hpp), several of them the
// blind study's own cases, and where a later round measures an effect's response.
#include "calibrate/attribution.hpp"
#include "calibrate/calibration_report.hpp"
#include "calibrate/decisions.hpp"
#include "calibrate/effect_responses.hpp"
#include "studies/report.hpp"
#include "test_support.hpp"

#include <gtest/gtest.h>

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <iostream>
#include <iterator>
#include <random>
#include <sstream>

namespace gapflow {
namespace {

TEST(AttributeDecision, AResidualWithinTheNoiseIsNotAttributedEvenToASignificantScore) {
  // Blind pass 6, null-3: chi^2 p 0.128 on the fitted points, corner rounding at adjusted p 0.038.
  EXPECT_EQ(should_attribute(0.128, true, 0.038, 0.05), Attribute::consistent_with_noise);
  // The same adjusted p where the residual is beyond the noise (pass 6's wallfriction-low had
  // chi2/nu 1.66 on 31, p 0.0117).
  EXPECT_EQ(should_attribute(0.0117, true, 0.038, 0.05), Attribute::yes);
  EXPECT_EQ(should_attribute(0.0117, true, 0.2, 0.05), Attribute::nothing_significant);
  EXPECT_EQ(should_attribute(0.0117, false, 0.0, 0.05), Attribute::nothing_visible);
  // The residual is asked first: within the noise, "consistent" whether anything is visible or not.
  EXPECT_EQ(should_attribute(0.5, false, 1.0, 0.05), Attribute::consistent_with_noise);
  // Both boundaries are no rejection: p = alpha does not reject at level alpha.
  EXPECT_EQ(should_attribute(0.05, true, 1e-9, 0.05), Attribute::consistent_with_noise);
  EXPECT_EQ(should_attribute(0.0117, true, 0.05, 0.05), Attribute::nothing_significant);
}

TEST(ShouldAttribute, ADecisiveScoreIsTriedWhereTheChiSquareIsWithinTheNoise) {
  // Blind pass 12's scatter-low: size scatter's adjusted p 5.6e-7, the fitted chi^2 p 0.11.
  EXPECT_EQ(should_attribute(0.11, true, 5.6e-7, 0.05), Attribute::consistent_with_noise);  // off by default
  EXPECT_EQ(should_attribute(0.11, true, 5.6e-7, 0.05, 1e-4), Attribute::decisive_score);
  // The nulls' smallest adjusted p over passes 8-12 (4.7e-4) stays below the option's reach.
  EXPECT_EQ(should_attribute(0.11, true, 4.7e-4, 0.05, 1e-4), Attribute::consistent_with_noise);
  // The threshold itself does not reject; nothing visible is never decisive.
  EXPECT_EQ(should_attribute(0.11, true, 1e-4, 0.05, 1e-4), Attribute::consistent_with_noise);
  EXPECT_EQ(should_attribute(0.11, false, 0.0, 0.05, 1e-4), Attribute::consistent_with_noise);
  // Beyond the noise the option changes nothing.
  EXPECT_EQ(should_attribute(0.0117, true, 0.2, 0.05, 1e-4), Attribute::nothing_significant);
  EXPECT_EQ(should_attribute(0.0117, true, 5.6e-7, 0.05, 1e-4), Attribute::yes);
}

TEST(ShouldAttribute, TheHeldOutRouteLooksWhereOnlyTheHeldOutPointsAreBeyondTheNoise) {
  // Blind pass 17's wallfriction-high: fitted chi^2 p 0.236, wall friction at adjusted p 0.0038,
  // the held-out points beyond the noise (final verdict "unexplained residual").
  EXPECT_EQ(should_attribute(0.236, true, 0.0038, 0.05), Attribute::consistent_with_noise);  // off
  EXPECT_EQ(should_attribute(0.236, true, 0.0038, 0.05, 0, 0.01), Attribute::held_out_residual);
  // The held-out points within the noise: nothing changes.
  EXPECT_EQ(should_attribute(0.236, true, 0.0038, 0.05, 0, 0.05), Attribute::consistent_with_noise);
  // The same condition on the candidate as ever: significant and visible.
  EXPECT_EQ(should_attribute(0.236, true, 0.05, 0.05, 0, 0.01), Attribute::nothing_significant);
  EXPECT_EQ(should_attribute(0.236, false, 0.0, 0.05, 0, 0.01), Attribute::nothing_visible);
  // Where the fitted points are beyond the noise, the ordinary route decides.
  EXPECT_EQ(should_attribute(0.0117, true, 0.0038, 0.05, 0, 0.01), Attribute::yes);
  EXPECT_EQ(should_attribute(0.0117, true, 0.2, 0.05, 0, 0.01), Attribute::nothing_significant);
  // A decisive score keeps its own route when the held-out points pass; when they do not, the
  // held-out route is the one named.
  EXPECT_EQ(should_attribute(0.236, true, 1e-6, 0.05, 1e-4, 0.5), Attribute::decisive_score);
  EXPECT_EQ(should_attribute(0.236, true, 1e-6, 0.05, 1e-4, 0.01), Attribute::held_out_residual);
}

TEST(FinalVerdict, ConsistentWithNoiseNeedsTheHeldOutPointsWithinTheNoiseToo) {
  // Blind pass 7, rolling-high: fitted chi^2 p 0.157, held-out (fresh seeds, the fit's uncertainty
  // included) p 0.00648, no effect
  // added. It was reported "consistent with noise"; the friction fit had absorbed the effect.
  VerdictEvidence rolling_high{.fitted_p_before = 0.157, .fitted_p_after = 0.157, .held_out_n = 12,
                               .held_out_fresh_p = 0.00648};
  EXPECT_TRUE(held_out_beyond_noise(rolling_high));
  EXPECT_EQ(final_verdict(rolling_high), "unexplained residual: the held-out points are beyond the noise");
  // Pass 7's null-4, the lowest held-out p of its nulls (0.23): still consistent.
  VerdictEvidence null_4{.fitted_p_before = 0.0865, .fitted_p_after = 0.0865, .held_out_n = 12, .held_out_fresh_p = 0.23};
  EXPECT_EQ(final_verdict(null_4), "consistent with noise");
  // p = alpha does not reject; without held-out points there is nothing to reject.
  VerdictEvidence at_alpha = null_4;
  at_alpha.held_out_fresh_p = 0.05;
  EXPECT_EQ(final_verdict(at_alpha), "consistent with noise");
  VerdictEvidence none_held = rolling_high;
  none_held.held_out_n = 0;
  EXPECT_FALSE(held_out_beyond_noise(none_held));
  EXPECT_EQ(final_verdict(none_held), "consistent with noise");
  // The fitted points beyond the noise and nothing added: unexplained, whatever the held-out say.
  VerdictEvidence beyond{.fitted_p_before = 0.001, .fitted_p_after = 0.001, .held_out_n = 12, .held_out_fresh_p = 0.6};
  EXPECT_EQ(final_verdict(beyond), "unexplained residual");
}

TEST(FinalVerdict, AnEffectFoundIsFlaggedWhenTheFitOrTheHeldOutPointsStayPoor) {
  // Pass 7's tilt-low: tilt added, fitted p after 0.99, held-out (fresh, fit-aware) p after 0.00519.
  VerdictEvidence tilt_low{.effects_added = 1, .fitted_p_before = 4.4e-9, .fitted_p_after = 0.99, .held_out_n = 12,
                           .held_out_fresh_p = 0.00519};
  EXPECT_FALSE(poor_fit(tilt_low));
  EXPECT_EQ(final_verdict(tilt_low), "effect found; the held-out points are still beyond the noise");
  tilt_low.held_out_fresh_p = 0.49;
  EXPECT_EQ(final_verdict(tilt_low), "effect found");
  // The fitted points still beyond 0.01 after the additions (pass 7's wallfriction-high, p 0.0094).
  VerdictEvidence poor{.effects_added = 1, .fitted_p_before = 1e-4, .fitted_p_after = 0.0094, .held_out_n = 12,
                       .held_out_fresh_p = 0.08};
  EXPECT_TRUE(poor_fit(poor));
  EXPECT_EQ(final_verdict(poor), "effect found, poor fit remains");
  // A fit alone (--max-effects 0) still reports the held-out points.
  VerdictEvidence fit_only{.attribution_allowed = false, .fitted_p_before = 0.3, .fitted_p_after = 0.3, .held_out_n = 12,
                           .held_out_fresh_p = 0.001};
  EXPECT_EQ(final_verdict(fit_only), "held-out points beyond the noise, not attributed (--max-effects 0)");
  fit_only.fitted_p_before = 0.001;
  EXPECT_EQ(final_verdict(fit_only), "residual not attributed (--max-effects 0)");
}

// Held-out points beyond the fitted range of a straight line y = a + b x (unit noise):
// the plain chi^2(n) test of their residual rejects a correct model far too often, the
// one that carries the fit's uncertainty holds its level, and both still see a missing term.
TEST(HeldOutTest, CarryingTheFitsUncertaintyHoldsItsLevelWhereTheDesignExtrapolates) {
  std::mt19937 rng(20261124);
  std::normal_distribution<double> noise(0.0, 1.0);
  const int n_fit = 12, n_held = 6, reps = 4000;
  Eigen::MatrixXd X(n_fit, 2), G(n_held, 2);
  for (int i = 0; i < n_fit; ++i) X.row(i) << 1.0, i / double(n_fit - 1);  // x in [0, 1]
  for (int i = 0; i < n_held; ++i) G.row(i) << 1.0, 2.0 + i / 2.0;        // x in [2, 4.5]
  auto rejections = [&](double curvature) {
    int plain = 0, aware = 0;
    for (int rep = 0; rep < reps; ++rep) {
      Eigen::VectorXd y(n_fit), yh(n_held);
      for (int i = 0; i < n_fit; ++i) y(i) = 1 + 2 * X(i, 1) + curvature * X(i, 1) * X(i, 1) + noise(rng);
      for (int i = 0; i < n_held; ++i) yh(i) = 1 + 2 * G(i, 1) + curvature * G(i, 1) * G(i, 1) + noise(rng);
      const Eigen::VectorXd theta = X.colPivHouseholderQr().solve(y);
      const Eigen::VectorXd r = yh - G * theta;
      plain += chi_square_of(r, 0).p < 0.05;
      aware += held_out_chi_square(r, G, X).p < 0.05;
    }
    return std::pair{plain / double(reps), aware / double(reps)};
  };
  const auto [plain_null, aware_null] = rejections(0.0);
  EXPECT_GT(plain_null, 0.25) << "the plain test should over-reject here";
  EXPECT_NEAR(aware_null, 0.05, 0.012);  // binomial se 0.0034 at 4000 draws
  const auto [plain_bent, aware_bent] = rejections(1.0);
  EXPECT_GT(aware_bent, 0.8) << "a missing curvature must still show";
  EXPECT_GE(plain_bent, aware_bent);
  std::cout << "held-out test rejections: correct model plain " << plain_null << ", fit-aware " << aware_null
            << "; missing curvature plain " << plain_bent << ", fit-aware " << aware_bent << "\n";
  // No fitted parameters: the plain test. No held-out points: nothing to test.
  const Eigen::VectorXd r = Eigen::VectorXd::Constant(n_held, 1.5);
  EXPECT_DOUBLE_EQ(held_out_chi_square(r, Eigen::MatrixXd(n_held, 0), Eigen::MatrixXd(n_fit, 0)).chi2,
                   chi_square_of(r, 0).chi2);
  EXPECT_EQ(held_out_chi_square(Eigen::VectorXd(0), Eigen::MatrixXd(0, 2), X).p, 1.0);
}

TEST(KeepDecision, BicMustFall) {
  EXPECT_EQ(keep_verdict({.bic_before = -184.5, .bic_after = -184.5, .held_out_n = 12, .held_before = 14, .held_after = 10},
                         10),
            Keep::bic_not_better);
  EXPECT_EQ(keep_verdict({.bic_before = 10, .bic_after = 12, .held_out_n = 0}, 10), Keep::bic_not_better);
}

TEST(KeepDecision, AnEffectFittedAtItsNeutralValueIsNeverKept) {
  // Blind pass 10's drag-high: spinning friction fitted at 0 mm (its neutral), BIC -152.9 -> -221.8,
  // held-out chi^2 62.7 -> 26.9.
  EXPECT_EQ(keep_verdict({.bic_before = -152.9, .bic_after = -221.8, .held_out_n = 12, .held_before = 62.7,
                          .held_after = 26.9, .at_neutral = true}, 10),
            Keep::at_neutral);
  EXPECT_EQ(keep_verdict({.bic_before = -152.9, .bic_after = -221.8, .held_out_n = 12, .held_before = 62.7,
                          .held_after = 26.9}, 10),
            Keep::keep);
}

TEST(KeepDecision, WithoutHeldOutPointsAFallingBicIsEnough) {
  EXPECT_EQ(keep_verdict({.bic_before = 10, .bic_after = 9, .held_out_n = 0}, 10), Keep::keep);
}

TEST(KeepDecision, HeldOutPointsThatDoNotFallVetoWithoutDecisiveEvidence) {
  EXPECT_EQ(keep_verdict({.bic_before = 10, .bic_after = 5, .held_out_n = 12, .held_before = 20, .held_after = 20}, 10),
            Keep::held_out_worse);
}

TEST(KeepDecision, TheToleratedRiseIsOneStandardDeviationOfTheHeldOutChiSquare) {
  // n = 12: sd = sqrt(24) = 4.90; a drop of exactly decisive_bic is decisive.
  const auto with_rise = [](double rise) {
    return KeepEvidence{.bic_before = 30, .bic_after = 20, .held_out_n = 12, .held_before = 20, .held_after = 20 + rise};
  };
  EXPECT_TRUE(decisive(with_rise(0), 10));
  EXPECT_EQ(keep_verdict(with_rise(4.85), 10), Keep::keep);
  EXPECT_EQ(keep_verdict(with_rise(4.95), 10), Keep::held_out_worse);
  EXPECT_FALSE(decisive({.bic_before = 30, .bic_after = 20.01}, 10));
}

TEST(KeepDecision, DecisiveEvidenceToleratesAHeldOutRiseWithinItsNoise) {
  // Pass 1's spinning friction: BIC 84.8 -> 17.7, held-out chi^2 11.0 -> 11.3 on 12 points (sd sqrt(24) = 4.9).
  const KeepEvidence spinning{.bic_before = 84.8, .bic_after = 17.7, .held_out_n = 12, .held_before = 11.0, .held_after = 11.3};
  EXPECT_TRUE(decisive(spinning, 10));
  EXPECT_EQ(keep_verdict(spinning, 10), Keep::keep);
  // The same rise with a BIC drop below decisive must fall instead.
  const KeepEvidence weak{.bic_before = 20, .bic_after = 15, .held_out_n = 12, .held_before = 11.0, .held_after = 11.3};
  EXPECT_FALSE(decisive(weak, 10));
  EXPECT_EQ(keep_verdict(weak, 10), Keep::held_out_worse);
  // A rise beyond one sd is a veto even with decisive evidence: pass 6's two-drag-gap, whose
  // gap offset alone cut BIC by 1291 and raised the held-out chi^2 from 945 to 1226. The loop
  // then tries the pair (decisive and vetoed by the held-out points: both must hold).
  const KeepEvidence gap{.bic_before = 1545.3, .bic_after = 254.0, .held_out_n = 12, .held_before = 944.8, .held_after = 1226.1};
  EXPECT_EQ(keep_verdict(gap, 10), Keep::held_out_worse);
  EXPECT_TRUE(decisive(gap, 10));
  // Held-out points that fall always pass once BIC fell.
  EXPECT_EQ(keep_verdict({.bic_before = 2, .bic_after = 1, .held_out_n = 12, .held_before = 30, .held_after = 29}, 10),
            Keep::keep);
}

TEST(WhichEffectToTry, TheContendersAreTheSignificantCandidatesBestScoresFirstAtMostMax) {
  // Blind pass 10, rolling-high, round 1 (visible candidates in the report's order): rolling
  // resistance, spinning friction, wall friction, size scatter, restitution, lateral tilt, gap
  // offset, linear drag, corner rounding, rolling contact.
  const std::vector<double> score{29.64, 1.87, 13.65, 1.35, 2.37, 0.23, 1.26, 35.55, 0.01, 25.05};
  const std::vector<double> p_adjusted{5.21e-7, 1, 0.0022, 1, 1, 1, 1, 2.48e-8, 1, 5.6e-6};
  EXPECT_EQ(contenders(score, p_adjusted, 0.05, 3), (std::vector<int>{7, 0, 9}));
  EXPECT_EQ(contenders(score, p_adjusted, 0.05, 10), (std::vector<int>{7, 0, 9, 2}));
  // One significant candidate: one contender (the round then fits it alone, as before rule 4).
  EXPECT_EQ(contenders(score, p_adjusted, 1e-7, 3), (std::vector<int>{7}));
  // None significant, or max 0: none. p_adjusted = alpha is not significant.
  EXPECT_TRUE(contenders(score, p_adjusted, 1e-9, 3).empty());
  EXPECT_TRUE(contenders(score, p_adjusted, 0.05, 0).empty());
  EXPECT_EQ(contenders({5, 6}, {0.05, 0.01}, 0.05, 3), (std::vector<int>{1}));
}

TEST(WhichEffectToTry, TheLowestFittedBicIsTriedNotTheBestScore) {
  // Contenders in score order; the second fits best. Rivals: within delta of the winner, itself included.
  const std::vector<bool> all(3, true);
  const FitChoice c = choose_by_fit({-239.8, -245.1, -242.0}, all, 3.84);
  EXPECT_EQ(c.winner, 1);
  EXPECT_EQ(c.rivals, (std::vector<int>{1, 2}));
  // Equal BICs: the first (the better score) wins; a difference of exactly delta is not a rival.
  const FitChoice tie = choose_by_fit({-10.0, -10.0, -6.0}, all, 4.0);
  EXPECT_EQ(tie.winner, 0);
  EXPECT_EQ(tie.rivals, (std::vector<int>{0, 1}));
  EXPECT_TRUE(choose_by_fit({}, {}, 3.84).rivals.empty());
  EXPECT_EQ(choose_by_fit({}, {}, 3.84).winner, -1);
}

TEST(WhichEffectToTry, AFitAtItsNeutralValueIsNeverTheOneTriedNorARival) {
  // Blind pass 10's drag-high pattern: a contender fitted at its neutral size gains BIC through the
  // free parameters alone. It must not win over a real fit, nor stand beside it as a rival.
  const FitChoice c = choose_by_fit({-221.8, -215.0, -213.0}, {false, true, true}, 3.84);
  EXPECT_EQ(c.winner, 1);
  EXPECT_EQ(c.rivals, (std::vector<int>{1, 2}));
  // All at neutral: the lowest BIC is named (the keep test then rejects it), alone.
  const FitChoice none = choose_by_fit({-5.0, -9.0}, {false, false}, 3.84);
  EXPECT_EQ(none.winner, 1);
  EXPECT_EQ(none.rivals, (std::vector<int>{1}));
}

TEST(AlternativesNotExcluded, AnotherFitThatAloneLeavesTheFittedPointsWithinTheNoiseIsNotExcluded) {
  // Fits in score order, the first tried. Fitted chi^2 p of each (blind pass 11's restitution-high
  // pattern: size scatter fitted alone leaves the fitted points within the noise too).
  const std::vector<double> p{0.62, 0.179, 0.0004};
  const std::vector<bool> all(3, true);
  EXPECT_EQ(alternatives_not_excluded(p, all, 0, 0.05), (std::vector<int>{1}));
  // The one tried is never its own alternative, whichever it is; p = alpha is within the noise.
  EXPECT_EQ(alternatives_not_excluded(p, all, 1, 0.05), (std::vector<int>{0}));
  EXPECT_EQ(alternatives_not_excluded({0.3, 0.05, 0.049}, all, 0, 0.05), (std::vector<int>{1}));
  // A fit at its effect's neutral value explains nothing by the effect (rule 4's eligibility).
  EXPECT_TRUE(alternatives_not_excluded(p, {true, false, true}, 0, 0.05).empty());
  // A fit without a chi^2 (NaN) is not within the noise; with none tried every within-noise fit counts.
  EXPECT_TRUE(alternatives_not_excluded({0.5, NAN}, {true, true}, 0, 0.05).empty());
  EXPECT_EQ(alternatives_not_excluded(p, all, -1, 0.05), (std::vector<int>{0, 1}));
  EXPECT_TRUE(alternatives_not_excluded({}, {}, 0, 0.05).empty());
}

TEST(FinalVerdict, AnEffectWithAlternativesNotExcludedWithholdsItsIdentityAfterThePoorFitAndHeldOutFlags) {
  VerdictEvidence e{.effects_added = 1, .fitted_p_before = 0.00999, .fitted_p_after = 0.607, .held_out_n = 12,
                    .held_out_fresh_p = 0.979, .alternatives = true};
  EXPECT_EQ(final_verdict(e), "effect found; these data do not exclude another effect in its place");
  // Both reservations where both hold: which effect acts, then how a drag depends on the speed.
  e.law_undetermined = true;
  EXPECT_EQ(final_verdict(e),
            "effect found; these data do not exclude another effect in its place; the drag's law in the speed is not "
            "established: a drag of another law may be acting");
  e.alternatives = false;
  EXPECT_EQ(final_verdict(e),
            "effect found; the drag's law in the speed is not established: a drag of another law may be acting");
  // A poor fit, or held-out points beyond the noise, say more: they come first.
  e.alternatives = true;
  e.held_out_fresh_p = 0.01;
  EXPECT_EQ(final_verdict(e), "effect found; the held-out points are still beyond the noise");
  e.fitted_p_after = 0.005;
  EXPECT_EQ(final_verdict(e), "effect found, poor fit remains");
  // Nothing added: the flag has nothing to qualify.
  VerdictEvidence none{.fitted_p_before = 0.3, .fitted_p_after = 0.3, .alternatives = true};
  EXPECT_EQ(final_verdict(none), "consistent with noise");
}

TEST(EffectResponses, ALaterRoundMeasuresAtTheNodesWithTheAddedEffectsAtTheirFittedValues) {
  const std::vector<ParameterSet> nodes{ParameterSet{}.with("particles.friction_particle", 0.3),
                                        ParameterSet{}.with("particles.friction_particle", 0.35)};
  // The fitted state: another friction (the fit's, not a node's) and a tilt of 5.4 deg.
  const ParameterSet fitted =
      ParameterSet{}.with("particles.friction_particle", 0.33).with("plane.lateral_tilt_deg", 5.4);
  EffectTerm tilt, wall;
  tilt.key = "plane.lateral_tilt_deg";
  wall.key = "particles.friction_wall", wall.neutral = 0.24;  // not fitted here: stays at its neutral value
  const std::vector<ParameterSet> at = nodes_with_effects(nodes, fitted, {tilt, wall});
  ASSERT_EQ(at.size(), 2u);
  for (std::size_t n = 0; n < 2; ++n) {
    EXPECT_DOUBLE_EQ(at[n].get("plane.lateral_tilt_deg", 0), 5.4);
    EXPECT_DOUBLE_EQ(at[n].get("particles.friction_wall", 0), 0.24);
    // Each node keeps its own free parameters: the finite differences pair runs at the nodes.
    EXPECT_DOUBLE_EQ(at[n].get("particles.friction_particle", 0), nodes[n].get("particles.friction_particle", 0));
  }
  EXPECT_EQ(nodes_with_effects(nodes, fitted, {})[1].label(), nodes[1].label());
}

TEST(EffectResponses, AMoreSizeBesideAMeasuredOneMovesToTheMiddleOfItsGap) {
  // Blind pass 20's rolling-high: rolling resistance's first step 0.01 was too weak, the range's
  // end (0.019 from neutral) became its step, and the refinement's half step, 0.0095, lay 0.0005
  // from the first step. Its segment's slope was the two sizes' noise over 0.0005, and the
  // interval came out [0.01059, 0.01082]. The half step now goes to the middle of 0..0.01.
  EXPECT_EQ(sizes_to_measure({0.0, 0.01, 0.019}, {0.0095}, 0.019 / 4), (std::vector<double>{0.005}));
  // The usual first measurement (only neutral measured): the step and its refinements, apart by
  // at least a quarter of the step by construction, are all kept.
  EXPECT_EQ(sizes_to_measure({0.0}, {2.0, 1.0, 4.0, 6.0}, 2.0 / 4), (std::vector<double>{1.0, 2.0, 4.0, 6.0}));
  EXPECT_EQ(sizes_to_measure({0.0}, {-0.4, -0.2, 0.4}, 0.4 / 4), (std::vector<double>{-0.4, -0.2, 0.4}));
  // A size measured already is not measured again; one close to the outermost size has no gap
  // to move into and is dropped; one whose gap's middle is close to a chosen size too.
  EXPECT_EQ(sizes_to_measure({0.0, 1.0, 2.0}, {2.0, 2.1, 1.0}, 0.25), (std::vector<double>{}));
  EXPECT_EQ(sizes_to_measure({0.0, 1.0}, {0.9, 0.45}, 0.25), (std::vector<double>{0.5}));
  // The first round's refinement of a step of 2 (0 and 2 measured): half step, the range's end
  // and halfway there, one step on the other side, all kept.
  EXPECT_EQ(sizes_to_measure({0.0, 2.0}, {1.0, 4.0, 6.0, -2.0}, 0.5), (std::vector<double>{-2.0, 1.0, 4.0, 6.0}));
  // A negative step (wall friction steps down): the same rules on the other side of neutral.
  EXPECT_EQ(sizes_to_measure({-0.19, -0.15, 0.0}, {-0.17, -0.075}, 0.15 / 4), (std::vector<double>{-0.075}));
  EXPECT_EQ(sizes_to_measure({-0.2, -0.1, 0.0}, {-0.095}, 0.2 / 4), (std::vector<double>{-0.05}));
}

TEST(EffectResponses, TheNodesNearestAFitAreRankedByItsFreeParametersAlone) {
  // Blind pass 10's rolling-high: surface nodes 0.30-0.50, the baseline fit 0.450 (signatures at
  // 0.45, 0.50, 0.40); every candidate's joint fit moved the friction to about 0.35.
  std::vector<ParameterSet> nodes;
  for (double f : {0.30, 0.35, 0.40, 0.45, 0.50}) nodes.push_back(ParameterSet{}.with("particles.friction_particle", f));
  Surface s;
  s.keys = {"particles.friction_particle"}, s.centre = {0.40}, s.half = {0.10};
  const ParameterSet baseline = ParameterSet{}.with("particles.friction_particle", 0.4502);
  EXPECT_EQ(nearest_nodes(nodes, s, baseline), (std::vector<std::size_t>{3, 4, 2}));  // 0.0498 from 0.50
  const ParameterSet moved = ParameterSet{}.with("particles.friction_particle", 0.345).with("particles.drag_per_s", 1.4);
  EXPECT_EQ(nearest_nodes(nodes, s, moved), (std::vector<std::size_t>{1, 0, 2}));  // effect keys play no part
  EXPECT_EQ(nearest_nodes(nodes, s, moved, 1), (std::vector<std::size_t>{1}));
  EXPECT_EQ(nearest_nodes(nodes, s, moved, 9).size(), 5u);
  // Measured again only when the nearest node changes: 0.4502 and 0.43 are both nearest 0.45
  // (the second nearest changes, 0.50 -> 0.40), 0.42 is nearest 0.40.
  const auto at = [](double f) { return ParameterSet{}.with("particles.friction_particle", f); };
  EXPECT_TRUE(nearest_same_node(nodes, s, baseline, at(0.43)));
  EXPECT_FALSE(nearest_same_node(nodes, s, baseline, at(0.42)));
}

TEST(EffectResponses, WithTwoFreeParametersASmallMoveAroundANodeMeasuresNothingAgain) {
  // A 3 x 3 grid (the baseline's with two free parameters): around the centre node the second
  // and third nearest change with the direction of every small move; the nearest does not.
  std::vector<ParameterSet> nodes;
  for (double f : {0.2, 0.3, 0.4})
    for (double w : {0.1, 0.2, 0.3}) nodes.push_back(ParameterSet{}.with("particles.friction_particle", f).with("particles.friction_wall", w));
  Surface s;
  s.keys = {"particles.friction_particle", "particles.friction_wall"}, s.centre = {0.3, 0.2}, s.half = {0.1, 0.1};
  const auto at = [](double f, double w) {
    return ParameterSet{}.with("particles.friction_particle", f).with("particles.friction_wall", w);
  };
  EXPECT_NE(nearest_nodes(nodes, s, at(0.31, 0.205)), nearest_nodes(nodes, s, at(0.295, 0.21)));
  EXPECT_TRUE(nearest_same_node(nodes, s, at(0.31, 0.205), at(0.295, 0.21)));
  EXPECT_FALSE(nearest_same_node(nodes, s, at(0.31, 0.205), at(0.36, 0.21)));
}

// Two exit_offset points (W/d 4 and 5), the data file of the report tests.
DataFile two_point_data() {
  const std::string points =
      "[[point]]\nW_over_d = 4\nobservable = \"exit_offset\"\nvalue = 1\nuncertainty = 0.1\n"
      "[[point]]\nW_over_d = 5\nobservable = \"exit_offset\"\nvalue = 2\nuncertainty = 0.1\n";
  return parse_data_file(testing::data_file_head("set = [\"particles.count=30\"]\nreplicates = 2\n") + points,
                         "t.toml", testing::source_path(""));
}

// A result with a model at both points, before and after (points.csv reads them).
CalibrationResult two_point_result() {
  CalibrationResult r;
  r.data_name = "t";
  r.model = "2d";
  for (ModelState* s : {&r.before, &r.after}) {
    s->prediction.value = s->prediction.fit = {1.1, 1.9};
    s->prediction.se_fit = {0.05, 0.05};
    s->prediction.valid = {true, true};
    s->whitened = {-1, 1};
  }
  r.before.fitted.chi.dof = 10;  // the residual's degrees of freedom (the detectability bound needs some)
  return r;
}

// Rule 5 in the report: the fits table gives each fit's chi^2, the round names the alternatives not
// excluded, the verdict line names them beside the effect, and summary.json carries them.
TEST(CalibrationReport, AlternativesNotExcludedAreNamedInTheRoundTheVerdictAndTheSummary) {
  const DataFile data = two_point_data();
  CalibrationResult r = two_point_result();
  r.alternatives = 2;
  Round round;
  round.best = "size_scatter";
  round.fits = {{"size_scatter", 0.077, -259.7, false, {39.89, 43, 0.607}},
                {"rolling_resistance", 0.004, -252.0, false, {47.1, 43, 0.31}},
                {"linear_drag", 0.4, -240.0, false, {60.2, 43, 0.042}}};
  round.alternatives = {"rolling_resistance"};
  round.rivals = {"size_scatter", "rolling_resistance"};
  round.decision = "test";
  r.rounds.push_back(round);
  AddedEffect scatter;
  scatter.effect = "size_scatter", scatter.key = "particles.size_scatter", scatter.value = 0.077;
  scatter.group = {"size_scatter"}, scatter.alternatives = {"rolling_resistance"};
  scatter.size_correlation = 0.48;
  r.effects.push_back(scatter);
  r.verdict = "effect found; these data do not exclude another effect in its place";
  testing::TempDir dir("gapflow-calibration-report-alternatives");
  write_calibration_outputs(data, r, dir.path(), false);
  std::ifstream md(dir / "report.md");
  const std::string text((std::istreambuf_iterator<char>(md)), std::istreambuf_iterator<char>());
  EXPECT_NE(text.find("| effect | fitted size | BIC | fitted chi2 / nu (p) | at neutral |"), std::string::npos) << text;
  EXPECT_NE(text.find("| rolling_resistance | 0.004 | -252.0 | 47.10 / 43 (0.31) |  |"), std::string::npos) << text;
  EXPECT_NE(text.find("the best score is the one tried"), std::string::npos) << text;
  EXPECT_NE(text.find("In place of size_scatter, these leave the fitted points within the noise (chi2 p >= alpha): "
                      "rolling_resistance."),
            std::string::npos)
      << text;
  EXPECT_NE(text.find("These data do not exclude rolling_resistance in its place: fitted instead of it (with "
                      "whatever was added before it), it leaves the fitted points within the noise"),
            std::string::npos)
      << text;
  // With the best score tried (contenders 1), the rivals are the score's, whatever was fitted for rule 5.
  EXPECT_NE(text.find("These data cannot rank them below the best (score within chi2_1(0.95) = 3.84 of size_scatter): "
                      "size_scatter, rolling_resistance."),
            std::string::npos)
      << text;

  const std::optional<std::string> python = find_python_with_matplotlib();
  if (!python) GTEST_SKIP() << "no python3 to parse summary.json";
  const std::string check = fmt::format(
      "import json; s = json.load(open('{0}')); "
      "assert s['alternatives'] == 2, s['alternatives']; "
      "assert s['effects'][0]['alternatives'] == ['rolling_resistance'], s['effects']; "
      "assert s['effects'][0]['size_correlation'] == 0.48, s['effects']; "
      "rd = s['rounds'][0]; assert rd['alternatives'] == ['rolling_resistance'], rd; "
      "assert abs(rd['fits'][2]['fitted_p'] - 0.042) < 1e-12 and rd['fits'][2]['fitted_dof'] == 43, rd['fits']",
      (dir / "summary.json").string());
  EXPECT_EQ(run_program({*python, "-c", check}, dir / "python.log"), 0);
}

// points.csv gives the fresh seeds' values beside the surface's (empty where none were simulated),
// and summary.json each state's surface window.
TEST(CalibrationReport, PointsCarryTheFreshValuesAndTheSummaryTheSurfaceWindows) {
  const DataFile data = two_point_data();
  CalibrationResult r = two_point_result();
  r.after.simulated_fresh.value = r.after.simulated_fresh.fit = {1.3, 2.2};
  r.after.simulated_fresh.se_fit = {0.07, 0.08};
  r.after.simulated_fresh.valid = {true, false};
  r.before.window_keys = r.after.window_keys = {"particles.friction_particle"};
  r.before.window_lo = {0.3}, r.before.window_hi = {0.5};
  r.after.window_lo = {0.35}, r.after.window_hi = {0.55};
  testing::TempDir dir("gapflow-calibration-report-fresh");
  write_calibration_outputs(data, r, dir.path(), false);
  std::ifstream csv(dir / "points.csv");
  std::string header, first, second;
  std::getline(csv, header), std::getline(csv, first), std::getline(csv, second);
  EXPECT_TRUE(header.ends_with(",residual_after,before_fresh,before_fresh_se,after_fresh,after_fresh_se")) << header;
  EXPECT_TRUE(first.ends_with(",-1,-1,,,1.3,0.07")) << first;  // no fresh runs before; the after's (linear scale)
  EXPECT_TRUE(second.ends_with(",1,1,,,,")) << second;          // the fresh runs gave no value at the second point

  const std::optional<std::string> python = find_python_with_matplotlib();
  if (!python) GTEST_SKIP() << "no python3 to parse summary.json";
  const std::string check = fmt::format(
      "import json; s = json.load(open('{0}')); "
      "assert s['before']['surface_window'] == {{'particles.friction_particle': [0.3, 0.5]}}, s['before']; "
      "assert s['after']['surface_window'] == {{'particles.friction_particle': [0.35, 0.55]}}, s['after']",
      (dir / "summary.json").string());
  EXPECT_EQ(run_program({*python, "-c", check}, dir / "python.log"), 0);
}

// The round table of report.md and summary.json's candidates carry the "left by the fit" share:
// as many cells as the header has, and summary.json stays valid JSON (parsed by python3).
TEST(CalibrationReport, TheCandidateTableAndSummaryCarryTheShareLeftByTheFit) {
  const DataFile data = two_point_data();
  CalibrationResult r = two_point_result();
  Round round;
  Candidate seen, unseen;
  seen.effect = "linear_drag", seen.key = "particles.drag_per_s", seen.step = 2, seen.visible = true;
  seen.score.statistic = 9, seen.score.p = 0.003, seen.score.projected_norm = 0.25, seen.score.signature_norm = 1;
  seen.score.se = 4;  // 1 / projected_norm
  unseen.effect = "restitution", unseen.key = "particles.restitution", unseen.step = -0.4;
  round.candidates = {seen, unseen};
  round.decision = "test";
  r.rounds.push_back(round);
  testing::TempDir dir("gapflow-calibration-report");
  write_calibration_outputs(data, r, dir.path(), false);

  std::ifstream md(dir / "report.md");
  std::string line, header, drag_row, restitution_row;
  while (std::getline(md, line)) {  // the first table (the rounds'); the detectability table follows it
    if (line.rfind("| effect |", 0) == 0 && header.empty()) header = line;
    if (line.rfind("| linear_drag |", 0) == 0 && drag_row.empty()) drag_row = line;
    if (line.rfind("| restitution |", 0) == 0 && restitution_row.empty()) restitution_row = line;
  }
  ASSERT_FALSE(header.empty());
  const auto bars = [](const std::string& s) { return std::count(s.begin(), s.end(), '|'); };
  EXPECT_NE(header.find("left by the fit"), std::string::npos);
  EXPECT_EQ(bars(drag_row), bars(header)) << drag_row;
  EXPECT_EQ(bars(restitution_row), bars(header)) << restitution_row;
  EXPECT_NE(drag_row.find("| 25 % |"), std::string::npos) << drag_row;

  // The detectability table: three cells a row, one row per candidate (no '|' inside a cell).
  std::ifstream md2(dir / "report.md");
  bool in_table = false;
  int rows = 0;
  while (std::getline(md2, line)) {
    if (line.rfind("| effect | neutral | smallest detectable departure", 0) == 0) in_table = true;
    else if (in_table && line.rfind("|---", 0) != 0 && line.rfind("| ", 0) == 0) {
      EXPECT_EQ(bars(line), 4) << line;
      ++rows;
    } else if (in_table && line.rfind("|---", 0) != 0) in_table = false;
  }
  EXPECT_EQ(rows, 2);

  // The verdict names the catalogue as the attribution's limit only where an effect was added.
  const auto verdict_line = [&](const std::filesystem::path& md_path) {
    std::ifstream in(md_path);
    std::string l;
    while (std::getline(in, l))
      if (l.rfind("**Verdict:", 0) == 0) return l;
    return std::string();
  };
  EXPECT_EQ(verdict_line(dir / "report.md").find("outside it"), std::string::npos);
  CalibrationResult found = r;
  AddedEffect drag;
  drag.effect = "linear_drag", drag.key = "particles.drag_per_s", drag.value = 1.7, drag.lo95 = 1.4, drag.hi95 = 2.6;
  drag.group = {"linear_drag"};
  found.effects.push_back(drag);
  testing::TempDir dir_found("gapflow-calibration-report-found");
  write_calibration_outputs(data, found, dir_found.path(), false);
  EXPECT_NE(verdict_line(dir_found / "report.md").find("an effect outside it that changes these observables the same way"),
            std::string::npos)
      << verdict_line(dir_found / "report.md");
  EXPECT_EQ(verdict_line(dir_found / "report.md").find("what remains may be such an effect"), std::string::npos);
  found.poor_fit = true;  // a poor fit after the addition: what remains may be outside the catalogue too
  testing::TempDir dir_poor("gapflow-calibration-report-poor");
  write_calibration_outputs(data, found, dir_poor.path(), false);
  EXPECT_NE(verdict_line(dir_poor / "report.md").find("Where the fit stays poor, what remains may be such an effect."),
            std::string::npos)
      << verdict_line(dir_poor / "report.md");

  const std::optional<std::string> python = find_python_with_matplotlib();
  if (!python) GTEST_SKIP() << "no python3 to parse summary.json";
  const std::string check = fmt::format(
      "import json; c = json.load(open('{0}'))['rounds'][0]['candidates']; "
      "assert abs(c[0]['left_by_fit'] - 0.25) < 1e-12 and c[1]['left_by_fit'] is None, c; "
      "d = json.load(open('{0}'))['detectability']; "
      "assert d[0]['visible'] and d[0]['min_departure'] > 4 and d[0]['within_range'] is not None, d; "
      "assert not d[1]['visible'] and d[1]['min_departure'] is None and d[1]['within_range'] is None, d",
      (dir / "summary.json").string());
  EXPECT_EQ(run_program({*python, "-c", check}, dir / "python.log"), 0);
}

}  // namespace
}  // namespace gapflow

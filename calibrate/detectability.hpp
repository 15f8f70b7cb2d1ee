// What a calibration's data could have seen: for every catalogue effect, the smallest departure
// from its neutral value that the loop's gates would pass with a stated power. A "consistent with
// noise" verdict then says what it rules out and what it does not (an effect this design cannot
// see in its plausible range is not excluded by the verdict, only unseen).
//
// Linearised at the baseline fit, an effect of departure a leaves the whitened residual
// a u~ (u~ = P u, its signature per unit with the fitted parameters projected out,
// attribution.hpp), a noncentrality lambda = (a / se)^2 with se = 1/|u~|, for both gates
// the loop puts before any attribution (decisions.hpp rule 1):
//   - the fitted points' chi^2 over nu = n + m - k degrees of freedom (m: measured free
//     parameters, data of the fit too) beyond its 1 - alpha quantile;
//   - the candidate's score (chi^2_1) beyond its Bonferroni level alpha / (visible candidates).
// The smallest detectable departure is sqrt(lambda*) se, lambda* the smallest noncentrality at
// which each has the stated power. Below it a departure passes the gates less often than that
// (about half as often at 0.8 times it). A lower bound on what the loop can see, not a promise: the
// loop then needs a lower BIC and held-out points that do not get worse, the effect must win
// against its rivals, and an effect that interacts with the fitted parameters can be absorbed by
// a large move of them that this linear view cannot see. Blind pass 7 (replayed): rolling
// resistance 0.0137 above neutral against a bound of 0.0066, absorbed by the friction fit moving
// 0.15 (the twin's oracle power, a refit over the friction grid with the effect simulated, 0.005);
// spinning friction 0.85 mm against 0.27 mm (oracle power 0.03).
// Only for candidates whose step moved the model beyond its noise ("visible"): for the others
// the signature is mostly noise and gives no se; the report says which step was not seen.
#pragma once

#include "calibrate/calibration.hpp"

#include <string>
#include <vector>

namespace gapflow {

// P(chi^2_dof(lambda) > chi^2_dof quantile 1 - alpha): the power of a chi^2 test at level alpha
// against a noncentrality lambda (boost::math::non_central_chi_squared). NaN for dof <= 0 or alpha
// outside (0, 1).
double chi_square_test_power(double lambda, double dof, double alpha);

// The smallest lambda at which the residual's chi^2 test (dof, level alpha) and the score test
// (1 degree of freedom, level score_alpha) each reach `power` (both together pass a little less
// often). Both powers rise with lambda. Infinite when dof <= 0 (the chi^2 gate then never
// rejects: chi_square_of gives p = 1) or when the levels or the power are not in (0, 1).
double min_detectable_noncentrality(double dof, double alpha, double score_alpha, double power);

// P(F(d1, d2; lambda) > the central F's quantile 1 - alpha): the power of Fisher's F test at level
// alpha against a noncentrality lambda in its numerator (boost::math::non_central_f), the
// denominator an independent chi^2(d2) / d2 of the same scale. NaN for d1 or d2 <= 0 or alpha
// outside (0, 1).
double f_test_power(double lambda, double d1, double d2, double alpha);

// The smallest lambda at which that F test reaches `power`. Infinite where it cannot (d1 or d2
// <= 0, alpha or power outside (0, 1)).
double min_detectable_noncentrality_f(double d1, double d2, double alpha, double power);

struct Detectability {
  std::string effect, unit;
  double neutral = 0;          // the template's value (key units)
  double lo = 0, hi = 0;       // the catalogue's plausible range (key units)
  bool visible = false;        // its step moved the model beyond its noise at the baseline fit
  bool absorbed = false;       // visible, but nothing of its signature is left by the fit (|P u| = 0)
  double min_departure = 0;    // visible: smallest |value - neutral| at which each gate has `power` (key units;
                               // infinite when no departure can be detected: no residual degrees of freedom)
  bool within_range = false;   // visible: neutral +- min_departure lies inside [lo, hi] on some side
  double largest_step = 0;     // the larger step measured (key units, signed departure from neutral)
  double largest_step_p = 1;   // its visibility p (paired chi^2 of the shift)
  bool step_reached_range_end = false;  // neutral + largest_step is an end of [lo, hi]
};

struct DetectabilityDef {
  double alpha = 0.05;  // the loop's level (CalibrationDef::alpha)
  double power = 0.8;   // the power at which a departure counts as detectable
};

// One entry per candidate of the round measured at the baseline fit (the first round), in its
// order; `residual_dof` = fitted points + measured free parameters - fitted parameters. Empty for no round.
std::vector<Detectability> detectability_at_baseline(const Round& baseline_round, int residual_dof,
                                                     const DetectabilityDef& def = {});

// One sentence per entry for the report ("at best from a departure of 0.012 (inside its plausible range [0, 0.02])").
std::string detectability_text(const Detectability& d);

}  // namespace gapflow

// Is each added effect one size across the design? A catalogue effect is a constant of the setup
// (a drag coefficient in 1/s, a rolling resistance, a tilt in degrees): the model says one size
// acts at every design point. An effect outside the catalogue that the loop reads as a catalogue
// one acts instead as a size that changes with the conditions. Blind pass 20's quadratic drag of
// 16 /m was read as a linear drag of 1.70 /s: a drag force k v^2 is one of k v per unit speed, so
// the linear size it mimics grows with the spheres' speed, steeper boards asking for more.
//
// The check: for every added effect and every design column (and the observable, where the points
// measure several), the effect's whitened sensitivity is split by the column's levels, one
// direction per level that has min_points_per_level fitted points the effect moves, and the score
// test (attribution.hpp, score_block) asks whether the residual after the fit wants different sizes
// at those levels. Every direction the fit used is projected out first (the free parameters, the
// added effects, a parameter left at an end of its range by a one-sided slope, and the other
// levels' part of the effect, which share one size, untested), so k tested levels give k - 1
// degrees of freedom. The statistic is then compared with the residual outside the fitted and the
// tested directions, Fisher's F on (k - 1, rest): exact for any common scale of the noise, so a
// residual beyond the stated noise everywhere is not read as a form mismatch, and a mismatch does
// not dilute its own test (it would, divided by the whole chi^2/nu). Without rest degrees of
// freedom, no test. The p-values are adjusted (Bonferroni) over every check of the calibration.
//
// What it can and cannot see. It is linear, at the fit. It sees a form mismatch only where the
// design spans conditions over which the two forms part by more than the noise; a mismatch along a
// direction no design column varies is invisible to it, and so is one the free parameters can take
// in. It treats the whitened residuals as independent, as every chi^2 of the loop does, though the
// observables of one design point share their runs (|rho| up to about 0.25 measured; the split by
// observable contrasts exactly those rows). Its power against a drag of another form was shown on
// the closed-form model at 16 and 4 model replicates, not at the 6 the blind study's design uses. A
// significant check says the effect's one size does not fit the design; it names no other effect.
// A check that flags nothing says only as much as its power: each check states the smallest spread
// of sizes across its column that it would flag with power 0.8 at the stated noise (a trend
// straight in the level's value; exact by the noncentral F; where the residual's own scale is
// below 1, the noise is smaller than stated and the spread smaller by sqrt(scale)), so that a
// reader can set it against what another form would need (a drag k v^2 read as linear needs a
// spread of about the spheres' relative speed difference across the column).
//
// The law in the speed. An effect whose force is a power of the speed (EffectDef::speed_law: the
// linear drag, force m gamma v) can be read with the wrong law: a drag m k v^n acts at speed v as a
// linear one of size k v^(n-1), so read as linear it asks for sizes that follow v^(n-1) across the
// design. Along the incline every speed on the board scales, to first order, as sqrt(g L sin theta)
// (rolling from rest in a fixed geometry; the friction and rolling resistance that oppose it, about
// mu cos theta, left out): the sizes asked for follow sin(theta)^((n-1)/2). Measured on blind null
// twins, J_mid (which at a fixed packing follows the outlet speed) spread 0.872-0.910 across 3-20 deg
// against sqrt(sin theta)'s 0.900 (results/form-check-wide-inclines). For the check along a column
// that sets plane.incline_deg, the sizes that law asks for (other_law_exponent), scaled so that the
// fit would read them as the fitted departure (the fit's coefficient on the effect, a mean weighted
// by the rows' sensitivities), give the check's noncentrality |P U s|^2 (no straight-trend
// approximation; linear at the fit, as the check is), and from it the check's power against that
// law at the stated noise. Below `power` the design does not determine the law: whatever the check
// says, the data could hold a drag of the other law, and the verdict says so after any failed test
// (poor fit, held-out points beyond the noise: decisions.hpp).
#pragma once

#include <Eigen/Dense>

#include <functional>
#include <limits>
#include <string>
#include <vector>

namespace gapflow {

struct DataFile;
struct Surface;
struct ModelState;

struct FormCheckDef {
  int min_points_per_level = 2;  // fitted points the effect moves that a level needs to be tested
  double alpha = 0.05;           // the loop's level, shared by the checks (Bonferroni)
  double power = 0.8;            // the power at which a spread of sizes counts as detectable
  double other_law_exponent = 2; // the law a speed-law effect is checked against: force ~ v^n (2: quadratic drag)
};

struct FormCheck {
  std::string effect;    // catalogue name of the added effect
  std::string column;    // the design column its sizes are split by, or "observable"
  int levels = 0;        // levels tested (each with a size of its own)
  double statistic = 0;  // score statistic on the whitened residual (chi^2-like, dof degrees of freedom)
  int dof = 0;           // degrees of freedom (levels - 1, fewer where the fitted directions mimic a split)
  int rest_dof = 0;      // degrees of freedom of the residual outside the fitted and tested directions (> 0)
  double scale = 1;      // that residual's chi^2 / rest_dof (1: the stated noise)
  double p = 1;          // P(F(dof, rest_dof) > statistic / (dof scale))
  double p_adjusted = 1; // p x the number of checks (Bonferroni), at most 1
  // What the check could see. A trend: the effect's departure from neutral straight in the level's
  // value (either order where a column has two levels that are not numbers), the departure at the
  // highest level exceeding the lowest's by a fraction `spread` of the fitted departure.
  double trend_noncentrality = 0;  // lambda of that trend per unit spread and per key unit^2 of departure
                                   // (|P U c|^2, whitened); NaN: levels with no order to trend along
  double spread_level = 0;         // the level the spread is computed at (alpha / the number of checks)
  double detectable_spread = 0;    // the smallest spread the check flags with power `power` at the
                                   // stated noise (1: the departures at the two ends differ by the
                                   // fitted departure); infinite where no spread can be seen (the
                                   // fitted size at neutral, or the trend taken in by the fitted
                                   // directions); NaN: no order
  // The law in the speed (speed-law effects along the incline; NaN elsewhere, or where a level is
  // not a number of degrees).
  double law_spread = std::numeric_limits<double>::quiet_NaN();  // the spread the other law asks:
      // (size at the highest level - at the lowest) / the one size the fit reads them as
  double law_noncentrality = std::numeric_limits<double>::quiet_NaN();  // lambda its sizes add per
      // key unit^2 of departure (0: the fitted directions take them in)
  double law_power = std::numeric_limits<double>::quiet_NaN();  // the check's power against it at
      // spread_level, at the stated noise
};

// One split (exposed for tests): r the whitened residual rows, X the fitted directions (its columns
// include u), u the effect's column, level the label of each point row (rows beyond it, the
// measurements', have none), informative_rows the rows that carry a value. dof 0: nothing tested
// (fewer than two levels, a split the fitted directions mimic, or no residual left to scale by).
// law_size, where given, is the size the other law asks at a level (any common scale; NaN for a
// level it cannot read): it sets law_spread and law_noncentrality.
using LawSize = std::function<double(const std::string& level)>;
FormCheck check_split(const Eigen::VectorXd& r, const Eigen::MatrixXd& X, const Eigen::VectorXd& u,
                      const std::vector<std::string>& level, int informative_rows, const FormCheckDef& def = {},
                      const LawSize& law_size = {});

// The linear size a drag ~ v^exponent mimics on an incline of `degrees`, up to a common factor:
// sin(theta)^((exponent - 1) / 2). NaN for a label that is not a number of degrees in (0, 90].
double speed_law_size(const std::string& degrees, double exponent);

// The split's p from its statistic S (dof) and the rest of the residual (rest_dof): Fisher's F on
// S / dof over rest / rest_dof. A rest at or below zero (rounding) with S beyond rounding of the
// residual's squared norm: p 0 (an infinite F); with S itself rounding: p 1.
double split_p(double statistic, double rest, int dof, int rest_dof, double residual_norm2);

// The smallest spread (FormCheck::detectable_spread) the check `c` flags with `power` at level
// `alpha` (the check's share of the Bonferroni level), for a fitted departure from neutral of
// `departure` key units: sqrt(lambda* / (trend_noncentrality departure^2)), lambda* the F test's
// smallest noncentrality with that power. Infinite where the trend moves nothing; NaN with no order.
double detectable_spread(const FormCheck& c, double departure, double alpha, double power);

// Every check of the final state `after` on `surface` (its effects the added ones), with each one's
// detectable spread at the Bonferroni level over them all; none without an added effect.
std::vector<FormCheck> form_checks(const DataFile& data, const Surface& surface, const ModelState& after,
                                   const FormCheckDef& def = {});

// Whether any check's adjusted p is below alpha.
bool form_differs(const std::vector<FormCheck>& checks, double alpha);

// The highest power against the other law among `effect`'s checks (NaN: none asked it: the design
// does not vary the incline, or leaves no residual to test in).
double law_power(const std::vector<FormCheck>& checks, const std::string& effect);

// Whether every added effect with a law in the speed has it established as the catalogue's: a
// check of it along the incline had `power` against the other law, and none of its checks that
// asked the law flags (adjusted p < alpha: the sizes follow the incline as another law's would).
// A flag here withholds the claim; it adds no finding (the form check's flags are out of the
// verdict, decisions.hpp rule 3). True where no such effect was added.
bool laws_established(const std::vector<FormCheck>& checks, const std::vector<std::string>& added, double power,
                      double alpha);

// The lowest law_power over the added effects that have a law in the speed (EffectDef::speed_law),
// 0 for one that no check could ask (nothing determines its law); NaN where none of them was added.
double lowest_law_power(const std::vector<FormCheck>& checks, const std::vector<std::string>& added);

}  // namespace gapflow

// Is each added effect one size across the design? A catalogue effect is a constant of the setup
// (a drag coefficient in 1/s, a rolling resistance, a tilt in degrees): the model says one size
// acts at every design point. An effect outside the catalogue that the loop reads as a catalogue
// one acts instead as a size that changes with the conditions. Blind pass 20's quadratic drag of
// 16 /m was read as a linear drag of 1.70 /s: a drag force k v^2 is one of k v per unit speed, so
// the linear size it mimics grows with the spheres' speed, steeper boards asking for more.
//
// The check: for every added effect and every design column (and the observable, where the points
// measure several), the effect's whitened sensitivity is split by the column's levels, one
// direction per level, and the score test (attribution.hpp, score_block) asks whether the residual
// after the fit wants different sizes at different levels. The common size is fitted already, so
// G levels give G - 1 degrees of freedom. The statistic is divided by max(1, chi^2/nu) of the
// residual outside the tested directions (the fitted points' chi^2 less the statistic, over their
// degrees of freedom less the test's): a residual beyond the noise everywhere is not a form
// mismatch, and the mismatch itself must not dilute its own test (dividing by the whole chi^2/nu
// would, since a strong mismatch raises it). The p-values are adjusted (Bonferroni) over every
// check of the calibration.
//
// What it can and cannot see. It is linear, at the fit. It sees a form mismatch only where the
// design spans conditions over which the two forms part by more than the noise; a mismatch along
// a direction no design column varies is invisible to it, and so is one the free parameters can
// take in. A significant check says the effect's one size does not fit the design; it does not
// say which effect would.
#pragma once

#include <string>
#include <vector>

namespace gapflow {

struct DataFile;
struct Surface;
struct ModelState;

struct FormCheckDef {
  int min_points_per_level = 2;  // points (fitted, moved by the effect) a level needs to get a size of its own
};

struct FormCheck {
  std::string effect;    // catalogue name of the added effect
  std::string column;    // the design column its sizes are split by, or "observable"
  int levels = 0;        // levels with a size of their own
  double statistic = 0;  // score statistic (whitened residual)
  double scale = 1;      // max(1, chi^2/nu) of the residual outside the tested directions: p is of statistic / scale
  int dof = 0;           // degrees of freedom (levels - 1, or fewer where the free parameters mimic a split)
  double p = 1;          // P(chi^2_dof > statistic)
  double p_adjusted = 1; // p x the number of checks (Bonferroni), at most 1
};

// Every check of the final state `after` on `surface` (its effects the added ones); none without
// an added effect. Effects at an end of their range are left out (their size cannot move).
std::vector<FormCheck> form_checks(const DataFile& data, const Surface& surface, const ModelState& after,
                                   const FormCheckDef& def = {});

// Whether any check's adjusted p is below alpha.
bool form_differs(const std::vector<FormCheck>& checks, double alpha);

}  // namespace gapflow

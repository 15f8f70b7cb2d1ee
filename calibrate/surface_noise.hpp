// Is the response surface's model noise what the runs show? The surface reports each point's
// variance as if its nodes were independent (fit.cpp, regress_point). Common random numbers run
// the same seeds at every node, and an observable that the seeds still govern when the parameter
// moves (the time to the first crossing: replicates correlate +0.77 between adjacent nodes in
// blind pass 15's store) keeps a shared error that does not average out over the nodes. This
// check fits the surface to each replicate's values alone (same nodes and window; every node of
// a point weighted alike, by the point's variance pooled over its nodes, so that the reported
// variance is unbiased for independent nodes and the weights do not depend on one replicate)
// and compares the spread of those fits at the baseline with the variance the same surface
// reports. Diagnostic only: no decision of the loop reads it.
#pragma once

#include "calibrate/fit.hpp"

#include <cmath>
#include <string>
#include <utility>
#include <vector>

namespace gapflow {

struct SurfaceNoiseCheck {
  int points = 0;             // fitted points with a value in every replicate at every node
  int replicates = 0;         // model replicates per node
  double median_ratio = NAN;  // median over those points of (replicates' spread)^2 / (reported variance)
  std::vector<std::pair<std::string, double>> by_observable;  // the same median per observable
};

// At the baseline fit (`base.params`, on the surface around `base.surface_at`). Independent nodes
// give a median near 1 (tests/test_surface_noise.cpp: 0.88-1.01 over five draws of 44 points at
// 12 replicates); an error shared by every node, up to 1/leverage (35/17 at the middle of five).
SurfaceNoiseCheck surface_noise_check(const DataFile& data, const BaselineFit& base);

// One log line: the ratios and, above 1.5, what that means.
std::string surface_noise_text(const SurfaceNoiseCheck& c);

}  // namespace gapflow

// Is the response surface's model noise what the runs show? The surface reports each point's
// variance as if its nodes were independent (fit.cpp, regress_point). Common random numbers run
// the same seeds at every node, and an observable that the seeds still govern when the parameter
// moves (the time to the first crossing in blind pass 15's store) keeps an error the nodes share,
// which does not average out over them.
//
// The check fits the baseline's surface (the same window of nodes) to each model replicate's
// values alone, every node of a point weighted alike, and compares the spread of those fits with
// the variance the same surface reports from the replicates' pooled variance, at the window's
// middle node, where a shared error shows most (there the reported variance is the leverage h
// times a node's, 17/35 for five nodes, while a shared error passes whole). With a correlation rho
// between any two nodes' replicates, spread / reported = 1 + rho (1/h - 1): that gives rho. The
// factor by which the surface understates the model's variance at the baseline fit x0 is then
// 1 + rho (1/h(x0) - 1): small where the fit sits on an end node (h = 31/35). That factor is the
// equally weighted surface's, as the loop's is since af66c1c (until then it weighted each node by
// its own standard error, for which this was an estimate). Diagnostic only: no decision of the
// loop reads it.
#pragma once

#include "calibrate/fit.hpp"

#include <cmath>
#include <string>
#include <vector>

namespace gapflow {

struct SurfaceNoiseGroup {
  std::string name;           // an observable, or "all"
  int points = 0;             // fitted points with a value in every replicate at every node of the window
  double correlation = NAN;   // rho: the replicates' correlation between nodes (independent nodes: about 0)
  double understated = NAN;   // the true model variance at the baseline over what the surface reports
};

struct SurfaceNoiseCheck {
  int nodes = 0;              // nodes in the baseline surface's window
  std::string problem;        // why there is no estimate (empty when there is one)
  SurfaceNoiseGroup all;      // every usable fitted point
  std::vector<SurfaceNoiseGroup> by_observable;
};

SurfaceNoiseCheck surface_noise_check(const DataFile& data, const BaselineFit& base);

// One log line: the estimates and, where the surface understates by more than 1.5 x, what that means.
std::string surface_noise_text(const SurfaceNoiseCheck& c);

}  // namespace gapflow

// Is the response surface's model noise what the runs show? Common random numbers run the same
// seeds at every node, and an observable that the seeds still govern when the parameter moves (the
// time to the first crossing) keeps an error the nodes share, which does not average out over them.
// The surface counts it from the replicates' correlation between nodes, pooled over each
// observable's points (calibrate/node_correlation.hpp); until that (blind pass 24 replayed,
// results/calibration-blind-pass24/replay-node-variance/) it took its nodes as independent.
//
// This check estimates the same thing another way, as one number per observable: it fits the
// baseline's surface (the same window of nodes) to each model replicate's values alone, every node
// of a point weighted alike, and compares the spread of those fits with the variance independent
// nodes would give, at the window's middle node, where a shared error shows most (there independent
// nodes pass the leverage h times a node's variance, 17/35 for five nodes, while a shared error
// passes whole). With a correlation rho between any two nodes' replicates, spread / independent =
// 1 + rho (1/h - 1): that gives rho. The factor by which independent nodes understate the model's
// variance at the baseline fit x0 is then 1 + rho (1/h(x0) - 1): small where the fit sits on an end
// node (h = 31/35). Set beside it is the factor the surface counts at x0 (its variance over
// independent nodes'). The two agree when the correlation is alike between any two nodes; where it
// falls off with the nodes' distance, as the first crossing's does, this check's one rho is the
// pairs' correlations weighted as the middle node's prediction weighs them, and its factor at x0
// differs from the surface's where x0 is elsewhere. Diagnostic only: no decision of the loop reads it.
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
  double understated = NAN;   // the true model variance at the baseline over what independent nodes give
  double counted = NAN;       // the surface's variance at the baseline over what independent nodes give
};

struct SurfaceNoiseCheck {
  int nodes = 0;              // nodes in the baseline surface's window
  std::string problem;        // why there is no estimate (empty when there is one)
  SurfaceNoiseGroup all;      // every usable fitted point
  std::vector<SurfaceNoiseGroup> by_observable;
};

SurfaceNoiseCheck surface_noise_check(const DataFile& data, const BaselineFit& base);

// One log line: the estimates and, where they exceed what the surface counts by more than 1.5 x, what that means.
std::string surface_noise_text(const SurfaceNoiseCheck& c);

}  // namespace gapflow

// How the model's replicates correlate between the response surface's nodes.
//
// Common random numbers run the same seeds at every node of the baseline grid, and an observable the
// seeds still govern when the parameter moves keeps part of its error from node to node. In blind
// pass 24's store (calibrate/node_correlation_check.py; results/calibration-blind-pass24/
// replay-node-variance/node_correlation.txt), the time to the first crossing's replicates correlate
// +0.67 between friction nodes 0.05 apart, +0.48 at 0.15, +0.22 at 0.40; J_mid's and the exit offset's and
// spread's stay within +-0.05 at every distance. A quadratic through such nodes does not average
// their shared error away, and counted as independent its variance was understated: at one free
// parameter's middle node a shared error passes whole where independent ones pass 17/35 of it
// (calibrate/surface_noise.hpp).
//
// Per observable, one correlation matrix between the nodes, pooled over its points: each point's
// replicates are centred and scaled at each node and stacked, so the matrix is a Gram matrix (positive
// semi-definite, unit diagonal) whatever the noise in it. Pooled, because from one point's 6
// replicates a correlation has a standard error of about 0.4; from a dozen points', about 0.1. The
// correlation depends on the observable and on how far apart the nodes are, not on the point, as far
// as the pass's store shows. A point whose replicates are not all finite at every node, or do not
// vary at one of them, is left out of the pooling (it still gets its observable's matrix); an
// observable with no point left gets the identity: its nodes counted as independent.
#pragma once

#include "calibrate/data_file.hpp"
#include "calibrate/evaluator.hpp"

#include <Eigen/Dense>

#include <string>
#include <vector>

namespace gapflow {

struct ObservableCorrelation {
  ObservableKind observable = ObservableKind::j_paper;
  int points = 0;          // points pooled (0: the identity)
  Eigen::MatrixXd matrix;  // [node][node], unit diagonal
  // The mean correlation of neighbouring nodes: for one free parameter, consecutive levels; with more,
  // the node pairs nearest each other (one grid step apart in one parameter). NaN with one node.
  double neighbours = 0;
};

struct NodeCorrelations {
  std::vector<ObservableCorrelation> observables;  // one per observable the data file has
  std::vector<std::size_t> of_point;                // per data point: its index in `observables`
  const Eigen::MatrixXd& at(std::size_t point) const { return observables[of_point[point]].matrix; }
};

// The correlations between `nodes` (parameter sets, for what counts as neighbours) from their predictions'
// replicates (Prediction::replicate_fit, the same seeds in the same order at every node).
NodeCorrelations node_correlations(const DataFile& data, const std::vector<ParameterSet>& nodes,
                                   const std::vector<Prediction>& preds);

// Each column of z (one point's replicates of one quantity, a row per replicate) centred and scaled to
// unit length, so that z^T z is their correlation matrix and one point's adds to a pooled Gram matrix
// with the weight of any other's; false (z left part done) when a column has no spread.
bool standardize_columns(Eigen::MatrixXd& z);

// One log line: the neighbours' correlation per observable and how many points it pools.
std::string node_correlation_text(const NodeCorrelations& c);

}  // namespace gapflow

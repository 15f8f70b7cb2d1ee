// The fits of the calibration loop, on a RESPONSE SURFACE of the model.
//
// Why a surface: a granular flow is chaotic, so common random numbers keep the
// packing but not the trajectory, and chi^2 evaluated run batch by run batch is
// rough: the first version minimised it point by point with BOBYQA, and on a twin
// two parameter sets 0.007 apart in wall friction gave chi^2 4.6 and 15.0, the
// fitted point scored chi^2/nu 0.91 on its own seeds and 3.15 on fresh ones (the
// optimiser had chased noise; calibrate/README.md). Instead, every point's
// prediction (fit scale) is regressed on the free parameters over a grid of
// nodes (a quadratic, every node weighted alike, its variance from each node's own and from the
// replicates' correlation between nodes, calibrate/node_correlation.hpp), and each effect
// adds a term, a shape-preserving interpolant in its size, measured by finite differences at the nodes
// next to the fit, under common random numbers. The surface is smooth (between an
// effect's measured sizes); NLopt's BOBYQA minimises its deviance (calibrate/deviance.hpp), and profiles
// are exact on it. Every fitted state
// is then re-scored by direct simulation on fresh seeds.
#pragma once

#include "calibrate/calibration.hpp"
#include "calibrate/deviance.hpp"
#include "calibrate/effect_term.hpp"

#include <Eigen/Dense>

#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace gapflow {

using Say = std::function<void(const std::string&)>;

// The model near the fit: quadratic in the free parameters, interpolated in each effect's size (EffectTerm), additive.
struct Surface {
  std::vector<std::string> keys;      // free parameters
  std::vector<double> centre, half;   // x' = (x - centre)/half in [-1, 1] over the nodes
  std::vector<double> lo, hi;         // the nodes' range of each free parameter (the surface holds there)
  std::vector<Eigen::VectorXd> coef;  // per point: 1, x'_k, x'_k x'_l (k <= l)
  std::vector<Eigen::MatrixXd> cov;   // per point: covariance of coef
  std::vector<bool> valid;            // at least half the nodes gave a value at this point (build_surface)
  std::vector<EffectTerm> effects;    // added (fitted) effects
  std::optional<double> lack_of_fit;  // pooled reduced chi^2 of the nodes about the quadratic (> 1: its excess added to
                                      // cov as a misfit); none where no point had more nodes than coefficients
  std::vector<ParameterSet> nodes;    // the nodes it goes through (empty for a surface made by hand)
  std::vector<Eigen::MatrixXd> node_weights;     // per point: coef = node_weights * the nodes' fit values (a zero
                                                 // column where a node has none)
  std::vector<std::vector<double>> node_variance;  // per point, per node: its fit value's se^2 (0 where none)
  std::vector<double> misfit_variance;  // per point: the lack of fit's excess as each node's own error (fit-scale^2; in cov)

  // Value, fit-scale value and its se at each point; params hold free keys and effect keys.
  // The se counts the noise the quadratic and an effect's term share: a term whose shifts are
  // paired with some of the surface's own nodes' runs (EffectTerm::paired_with; the first effect
  // the loop adds, measured at the baseline's grid nodes) has those runs with a minus sign where the
  // quadratic has them with a plus. Added as independent, as until this was found (blind pass 24
  // replayed, results/calibration-blind-pass24/replay-fresh-points/), one free parameter's
  // surface stated about 1.15 sigma^2 at its centre node where the prediction's variance is about
  // 0.37 sigma^2 (sigma^2: one node's mean's variance; calibrate/README.md).
  Prediction predict(const ParameterSet& params, const DataFile& data) const;
  // The same with `value` left on the fit scale (no data file needed).
  Prediction predict_fit(const ParameterSet& params) const;
  // The quadratic's variance at point i as if its nodes' values were independent (each node's se^2 times
  // its weight squared), without the lack-of-fit widening: what the surface stated until the
  // replicates' correlation between nodes was counted (calibrate/surface_noise.hpp compares the two).
  double independent_nodes_variance(const ParameterSet& params, std::size_t i) const;
  // At `params`: how many of the quadratic's covariances with the effects' shifts are held at their bound.
  // Each comes from a few runs' se's; where they disagree the bound keeps the variance from going negative,
  // and a bound that binds often says the stated se rests on the bound rather than the estimate.
  SharedCovarianceBound shared_covariance_bound(const ParameterSet& params) const;
  // The lack of fit's share of the quadratic's variance at point i (0 where it is within the noise).
  double misfit_part(const ParameterSet& params, std::size_t i) const;
  // d(fit)/d(key) of a free parameter at `params`, per point.
  std::vector<double> derivative(const ParameterSet& params, std::size_t k) const;
};

struct BaselineFit {
  Surface surface;
  ParameterSet params;                // fitted free parameters
  std::vector<ParameterSet> nodes;    // grid nodes next to the fit (signatures are taken there)
  std::vector<Prediction> node_predictions;
  std::vector<ParameterSet> grid;     // every node of the baseline grid, all simulated (responses are measured
                                      // at the ones nearest a later fit: EffectResponses::reference_with)
  std::vector<Prediction> grid_predictions;
  ParameterSet surface_at;            // the grid node `surface` is built around (the best by chi^2)
};

// The surface through the baseline grid's nodes around `at`, without effects: one free parameter,
// the five consecutive nodes around the node nearest `at` (all of them if fewer); two or three,
// every node (three levels each: a quadratic needs them all). Made from the baseline's runs: no new
// runs. A fit is bounded to its surface's nodes; an effect's joint fit that ends at that bound is
// fitted again on the surface around where it stopped (calibration.cpp, fit_trial).
Surface surface_around(const DataFile& data, const BaselineFit& base, const ParameterSet& at);
// The indices in base.grid of the nodes surface_around(data, base, at) goes through.
std::vector<std::size_t> surface_window(const DataFile& data, const BaselineFit& base, const ParameterSet& at);
// Whether `p` sits on one of `s`'s bounds in a free parameter where the baseline grid goes further.
bool at_inner_bound(const Surface& s, const BaselineFit& base, const ParameterSet& p);

// The (up to) `count` of `nodes` nearest `at` in the surface's scaled free parameters, nearest first.
std::vector<std::size_t> nearest_nodes(const std::vector<ParameterSet>& nodes, const Surface& s, const ParameterSet& at,
                                       std::size_t count = 3);
// Whether `a` and `b` are nearest the same node. An effect's response measured around `a` is
// measured again for a fit at `b` when they are not (not when the second or third nearest
// changes: with two or three free parameters those change with every small move).
bool nearest_same_node(const std::vector<ParameterSet>& nodes, const Surface& s, const ParameterSet& a,
                       const ParameterSet& b);

// The baseline grid's values of one free parameter: alone, its step from lo (at most
// grid_max levels, spread evenly if more would be needed); with others, lo, mid, hi.
std::vector<double> grid_levels(const FreeParameter& f, bool alone, int grid_max);

// Grid over the free parameters' ranges (one parameter: spacing `step`, at most
// def.grid_max nodes; two or three: 3 levels each), all in one batch of runs (the
// same nodes for every data file of this design, so calibrations sharing a store
// share them); the surface through the best node's neighbourhood; BOBYQA on it.
BaselineFit fit_baseline(const DataFile& data, const CalibrationDef& def, Evaluator& ev, const Say& say);

// Minimise the deviance of the surface over the free parameters and the given effects
// (starting at `start`); BOBYQA, deterministic.
// `fixed` (optional) names a key held at its value in `start` (profiles).
ParameterSet fit_surface(const DataFile& data, const Surface& s, const ParameterSet& start, const std::string& fixed = "");

// Fit of effect term `e` of the surface with the free parameters, and its profile
// interval: the connected range of values around the estimate whose deviance, minimised
// over everything else, is within 3.84 x max(1, chi2/nu) of the estimate's. The profile is
// scanned at 81 values over the effect's whole range, and the fit restarts from the scan's
// best point when that is lower than where BOBYQA stopped (the deviance has kinks at the
// measured sizes).
struct ProfileInterval {
  double lo = 0, hi = 0;
  bool bounded_lo = true, bounded_hi = true;  // false: the range's end was reached
};
struct EffectFit {
  ParameterSet params;       // free parameters and every effect's size
  ProfileInterval interval;  // of effect e
  bool restarted = false;    // the scan found a lower deviance than the first fit
};
EffectFit fit_effect(const DataFile& data, const Surface& s, const ParameterSet& start, std::size_t e,
                     int fitted_parameters);

}  // namespace gapflow

// An effect term of a calibration's response surface: one effect's measured shifts of every
// point, interpolated in its size (calibrate/fit.hpp puts it beside the free parameters' quadratic).
#pragma once

#include "calibrate/evaluator.hpp"

#include <Eigen/Dense>

#include <cstddef>
#include <memory>
#include <string>
#include <vector>

namespace gapflow {

// One point's response through an effect's measured sizes: a shape-preserving cubic (effect_term.cpp).
struct SmoothResponse;

// How the errors of a term's sizes' shifts correlate, pooled over a group of points (one observable's):
// every size's moved runs are paired with the same nodes' runs on the same seeds, so each shift carries
// minus those runs' noise, and each moved run keeps some of its partner's and its neighbours' (common
// random numbers). For moved runs that keep nothing of their partners the shifts correlate 1/2.
struct SizeCorrelation {
  // Fewest points pooled for the correlation to be counted: from one point's 18 pairs a correlation's
  // se is about 0.2, which would understate the variance by a fifth at two se's; from 6, about 0.08.
  static constexpr int kMinPoints = 6;
  int points = 0;          // points pooled
  Eigen::MatrixXd matrix;  // [size][size] over EffectTerm::offsets, unit diagonal (neutral's row the
                           // identity's), each entry within [0, 1]; empty below kMinPoints (the bound)
  // [size] over EffectTerm::offsets: the covariance of a partner (an unmoved run) with its pair's
  // difference over that difference's variance, pooled over the group's points. -1/2 whatever the
  // moved runs keep of their partners where they vary as much as their partners do; more negative
  // where they vary less (below -1 where they keep much of a noisier partner: held at -1), toward 0
  // where more. Empty where the partners are not known or too few points pooled (-1/2 then).
  std::vector<double> partner_share;
};

// An effect term of the surface: the shift of every point's fit-scale value when
// the effect's key moves from its neutral value, measured under common random
// numbers at a few sizes and interpolated between them (extrapolated linearly
// with the end segments). A candidate starts with one size (its physical step:
// `slope` is its signature); an effect the loop adds is measured at more sizes
// across its range, because few effects act linearly over it: a lateral tilt
// moves where spheres leave linearly but slows the flow quadratically (J is even
// in the tilt: the board mirrored is the same board).
// Between the sizes: with four or more, a shape-preserving cubic (PCHIP, Boost.Math:
// monotone where the measured shifts are, never beyond its neighbours; its end slopes from the
// three end sizes, effect_term.cpp end_slope); with fewer, a straight line. A straight line through a curved response is biased toward
// neutral: the tilt's quadratic J through 0, 2, 4, 6 deg reads 4.48 deg where 4.56
// was planted, which blind passes 15-18 fitted (4.478 for 4.559 in pass 18's
// tilt-high; 6 of 8 tilt intervals missed, all toward neutral).
struct EffectTerm {
  std::string effect, key;
  double neutral = 0;             // the template's value (the term is 0 there)
  double lo = 0, hi = 0;          // plausible range (key units)
  std::vector<double> slope;      // per point: shift at the first step / step
  std::vector<double> slope_se;   // per point (paired replicate differences)
  std::vector<double> offsets;    // sizes measured, key - neutral, ascending, 0 included
  std::vector<std::vector<double>> shift, shift_se;  // [size][point], fit scale (0 at offset 0)
  std::vector<std::shared_ptr<const SmoothResponse>> smooth;  // [point] (4+ sizes, finite shifts; else null:
                                                              // a straight line), made by add_size
  // The nodes whose runs every size's shifts pair the moved runs with (replicate by replicate, on
  // the data file's seeds); empty where those runs are on seeds of their own. Where they are
  // baseline grid nodes, the surface's quadratic goes through the same runs, and the two parts of
  // a prediction share their noise (Surface::predict_fit).
  std::vector<ParameterSet> paired_with;
  // The paired differences behind each size's shift (fit scale), [size][point][pair], the pairs in one order at
  // every size (node by node, replicate by replicate; NaN where a run is missing); empty at a size
  // measured otherwise (a signature's, and neutral, whose shift is 0 exactly). Where every size but
  // neutral has them, their correlation is counted in the variance (`size_correlation`).
  std::vector<std::vector<std::vector<double>>> pairs;
  std::vector<std::size_t> pooled_in;  // per point: the group whose points the correlation pools (empty: one group)
  // [point][pair]: each pair's unmoved run (fit scale, NaN where missing), in the pairs' order, node
  // by node over the paired_with nodes, the same number at each; empty where not known (a term on
  // seeds of its own pairs with no surface node). For SizeCorrelation::partner_share.
  std::vector<std::vector<double>> partners;
  std::vector<SizeCorrelation> size_correlation;  // [group]; empty where not every size has its pairs

  // A term measured at one step: shift = slope * step.
  static EffectTerm single_step(std::string effect, std::string key, double neutral, double lo, double hi, double step,
                                std::vector<double> slope, std::vector<double> slope_se);
  // The mean correlation of neighbouring sizes' errors in `group` (neutral left out: its shift is
  // exact); NaN where not counted, or with one size beside neutral. With no group, the mean over the
  // groups weighted by their points.
  double neighbour_correlation(std::size_t group) const;
  double neighbour_correlation() const;
  // Add the shifts measured at offset `da` (kept sorted), with the paired differences they are the
  // means of where given ([point][pair]); the interpolants and the sizes' correlation are made anew.
  void add_size(double da, std::vector<double> shift_at, std::vector<double> se_at,
                std::vector<std::vector<double>> pairs_at = {});
  // Shift at point i for an offset da, and its variance through the interpolant's weights on the
  // sizes (for a straight line 1 - w and w; the cubic also leans on the next sizes, its weights by
  // finite differences, the larger one-sided one where it is not smooth): with the sizes'
  // correlation where it is counted (size_correlation), else the largest over correlations in
  // [0, 1]. That bound stated 1.3-1.8 times the shift's spread between the sizes where the shifts
  // correlate 1/2, and up to 2.2 times where they correlate 0.9, since where the weights differ in
  // sign it takes the errors as independent where they cancel (tests/test_calibration_observables.cpp,
  // TheSizesCorrelationReadOffTheirPairs...). Before 422ca03
  // (blind passes up to 20) the two neighbours' standard errors were interpolated linearly, which
  // understated the cubic's by 14 % at 3 deg on the tilt's quadratic.
  // With `paired_covariance`, also the covariance of that shift with the mean of one paired node's
  // runs at point i (each such node alike; 0 without paired nodes): sum_j w_j c_j shift_se_j^2 over
  // the same weights w_j, c_j the size's partner share (SizeCorrelation), -1/2 where not known
  // (derived in effect_term.cpp). Negative: a node's runs enter the shift with a minus sign.
  double response(std::size_t i, double da, double& variance, double* paired_covariance = nullptr) const;

 private:
  // The interpolant's weights on the sizes at offset da, and the shift there.
  std::vector<double> weights(std::size_t i, double da, double& value) const;
};


}  // namespace gapflow

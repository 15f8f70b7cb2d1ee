// How the calibration loop measures what an effect does to the model: finite
// differences under common random numbers at the baseline grid's nodes next to
// the fit (calibrate/fit.hpp), every moved run paired with the same node's
// unmoved run on the same seeds.
//
//   signatures: every applicable catalogue effect moved by its physical step (and,
//     where that step is lost in the noise, by its range's end): its slope per
//     point, whether it moved the model beyond its noise, and a one-size term;
//   responses: an effect about to be added, measured at more sizes across its
//     range, so that its size is fitted on its measured response.
//
// The reference: the baseline grid's nodes nearest the fit, with the effects already added
// set to their fitted values. An effect's response depends on the free parameters it is
// measured at (a rolling resistance slows a flow of rough spheres differently from one of
// smooth ones), and the surface adds it unchanged wherever they go; so where an effect's
// joint fit moves them to other nodes, its response is measured again there and the fit
// repeated (calibration.cpp, fit_trial). Blind pass 10's rolling-high: the baseline put the
// friction at 0.45 (nodes 0.40-0.50) for a true 0.33; every candidate's fit moved it to
// about 0.35. Effects need not add up: a rolling resistance may slow spheres on a board
// tilted sideways by 5 deg differently from one that is not. Our reading of blind
// pass 6's two-tilt-rolling (not measured apart): with a tilt added, a planted
// rolling resistance measured on the untilted nodes cut BIC by 30 and raised the
// held-out chi^2 from 48 to 168. The first round's reference is the baseline's own
// nodes (no runs); a later round's costs one more batch of the nodes' runs, and
// only the candidates about to be fitted are measured there: which ones those are
// is still decided on the signatures measured at the baseline (re-measuring all ten
// would cost a second signature batch, ~2000 runs).
// A term measured anew (a later round's, or the first round's with the signatures on seeds of
// their own) has the step and the refinement sizes only, not the first step beside the range's
// end that a weak signature's own term holds.
//
// Shared noise (CalibrationDef::independent_signatures: on by default from blind pass 19's
// decision; --shared-signatures pairs with the baseline's runs, as every pass up to 18). The score test
// (attribution.hpp) projects the residual r = data - surface on a signature g, the moved runs
// less the unmoved runs at the nearest nodes. On the baseline's seeds, those unmoved runs are
// the very runs the surface was fitted through: r carries minus their noise, and so does g,
// where the moved runs do not repeat it (a simulator's trajectories part within a few
// collisions, so common random numbers cancel little of it). Then E[g.r] > 0 on a correct
// model: every score leans toward its step, most for the weak signatures, and the test rejects
// too often. On seeds of their own (the default) the signatures' moved and unmoved runs are made
// there, and they serve the score, the visibility and the choice of step; the response an effect
// is fitted with is measured anew against the nodes' runs on the baseline's seeds (667bb64;
// until then the signature's sizes were kept and the others added on the baseline's seeds, a
// term of mixed pairing). Whether the fit is better so or with every size on the own seeds is
// open: the baseline's pairing largely cancels the nodes' noise in the prediction, and it brings
// the same shared noise into the linearised size the fit finds (calibrate/README.md, step 4).
#pragma once

#include "calibrate/calibration.hpp"
#include "calibrate/fit.hpp"

#include <optional>
#include <string>
#include <vector>

namespace gapflow {

struct EffectDef;

// Where responses are measured and the model's unmoved predictions there.
struct Reference {
  std::vector<ParameterSet> nodes;
  std::vector<Prediction> predictions;  // one per node: the partners of the moved runs
  ParameterSet anchor;                  // the fitted point the nodes were chosen around
  std::optional<std::uint64_t> seed;    // the base seed of those runs and of the moved ones (none: the data file's)
};

// The baseline's nodes with the effects' keys set to their values in `effects_at` (an effect
// it lacks at its neutral value); the nodes keep their own free parameters.
std::vector<ParameterSet> nodes_with_effects(const std::vector<ParameterSet>& nodes, const ParameterSet& effects_at,
                                             const std::vector<EffectTerm>& effects);

// The sizes (offsets from neutral) at which an added effect is measured beyond
// its step: half the step; the range's end on the step's side when it lies
// beyond 1.25 steps (and halfway there when beyond 2.5); one step, or what
// there is of it, on the other side of neutral when the range goes there.
std::vector<double> refinement_offsets(const Candidate& c, const EffectDef& e);

// Of the `wanted` sizes (offsets from neutral), those worth measuring beside the `measured` ones
// (0 included), ascending: a size closer than `min_spacing` to a measured or already chosen one
// moves to the middle of the gap between measured sizes that holds it, and is dropped if that is
// close too. Two sizes close together leave a segment whose slope is their noise over their
// distance, and the fit finds a narrow false well in it: blind pass 20's rolling-high had rolling
// resistance measured at 0.0095 beside its first step 0.01 (the step moved to the range's end,
// 0.019, whose half is 0.0095), and its interval came out [0.01059, 0.01082] where the data's
// signal (lambda 17) allows one about 40 times wider.
std::vector<double> sizes_to_measure(const std::vector<double>& measured, const std::vector<double>& wanted,
                                     double min_spacing);

class EffectResponses {
 public:
  EffectResponses(const DataFile& data, const CalibrationDef& def, Evaluator& ev, Say say)
      : data_(data), def_(def), ev_(ev), say_(std::move(say)) {}

  // The baseline's nodes as a reference (their runs are made).
  static Reference baseline_reference(const BaselineFit& base) { return {base.nodes, base.node_predictions, base.params, {}}; }
  // The same nodes run again on base seed `seed` (one batch): moved runs paired with these share
  // no noise with the baseline's surface (CalibrationDef::independent_signatures).
  Reference on_own_seeds(const Reference& at, std::uint64_t seed);
  // The (up to) three baseline grid nodes nearest `fitted`'s free parameters, with the added effects at
  // their values in `fitted`: one batch of runs (none new for baseline nodes without effects).
  Reference reference_with(const BaselineFit& base, const ParameterSet& fitted, const std::vector<EffectTerm>& effects);

  // Every applicable catalogue effect moved by its physical step at the reference (all in one
  // batch); a step lost in the noise measured again at its range's end. `terms` gets each
  // candidate's one- or two-size term.
  std::vector<Candidate> signatures(const Reference& at, std::vector<EffectTerm>& terms);
  // Add the refinement sizes to a candidate's term (measured at `at`; the term's range shrinks
  // to where every point still makes a scenario).
  void refine(EffectTerm& term, const Candidate& c, const Reference& at);
  // A candidate's whole term measured at `at`: its step and the refinement sizes, in one batch.
  EffectTerm measure_term(const Candidate& c, const Reference& at);

 private:
  double valid_far_step(const Candidate& c) const;
  std::optional<double> valid_offset(const std::string& key, double neutral, double offset) const;
  bool valid_everywhere(const std::string& key, double value) const;
  void measure_signatures(std::vector<Candidate>& cands, const std::vector<std::size_t>& which, const Reference& at,
                          std::vector<EffectTerm>& terms, const std::string& why);
  void add_sizes(EffectTerm& term, const Candidate& c, const std::vector<double>& offsets, const Reference& at);
  // `sets` run on the reference's seeds.
  std::vector<Prediction> evaluate_at(const Reference& at, const std::vector<ParameterSet>& sets);
  // Runs behind a batch of `parameter_sets` (every point, every replicate): for the log.
  std::size_t batch_runs(std::size_t parameter_sets) const;

  const DataFile& data_;
  const CalibrationDef& def_;
  Evaluator& ev_;
  Say say_;
};

}  // namespace gapflow

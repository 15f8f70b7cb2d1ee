// Twins: measured-data files made by a model with hidden effects, for testing the
// calibration loop where the truth is known. The data file a twin writes says
// nothing about the effects in it; the truth goes to a separate JSON file that
// `gapflow calibrate` never reads. The design (points, observable, free
// parameters, held-out points) is the one of the data file given, as a user made it.
#pragma once

#include "calibrate/data_file.hpp"
#include "calibrate/evaluator.hpp"

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

namespace gapflow {

struct TwinDef {
  std::string name;                  // [data] name of the twin
  ModelKind model = ModelKind::box2d;// the model that makes the data (3d for the non-identical twin)
  std::uint64_t seed = 1;            // draws the hidden sizes and the free parameters' true values
  std::vector<std::string> effects;  // catalogue effects to plant: "name" (size drawn), "name:low", "name:high", "name=value"
  std::vector<std::string> set;      // overrides planted as they are (e.g. an effect outside the catalogue)
  int replicates = 10;               // runs per point behind each value (its se from their spread)
  bool draw_free = true;             // the free parameters' true values drawn inside their ranges
  // The [model] seed the twin's data file gives the calibrations of it (none: the design's). A blind
  // study whose twins all carry the design's seed calibrates every twin against one draw of the
  // model's noise (README, Calibration: what the blind study showed); a seed per twin samples it.
  std::optional<std::uint64_t> model_seed;
};

struct PlantedValue {
  std::string name;  // catalogue effect, "free" or "set"
  std::string key;
  double value = 0, neutral = 0;
};

// How strongly the planted effects show in the twin's data: the same runs (same
// seeds) without them, the free parameters refitted, in units of the noise a
// calibration of the twin sees. Computed with the truth, for judging the blind
// study; `gapflow calibrate` never reads it.
struct PlantedSignal {
  bool known = false;     // false: nothing planted (a null twin, or the other model's data as they are)
  double chi2 = 0;        // lambda = min over the free parameter of chi^2(data, model without the effects) less the
                          // paired runs' own noise, over the fitted points, plus the measurement's chi^2 about the
                          // true value where the twin carries a reading: the noncentrality (dimensionless)
  int points = 0;         // fitted points
  double critical = 0;    // the score test's threshold, Bonferroni over every applicable effect (the loop: visible ones)
  double oracle_power = 0;// P(score > critical) for a score test that knew the planted signature
};

struct TwinTruth {
  std::vector<PlantedValue> planted;
  // Per free parameter of the design: what an independent measurement of its true value read
  // (the design's measured_se of error, drawn from the twin's seed), or NaN
  // when the design declares no measurement. Written into the twin as `measured`.
  std::vector<double> measured;
  std::uint64_t model_seed = 0;  // run.seed of the twin's runs (never the calibration's)
  PlantedSignal signal;
};

// The planted effects' noncentrality over the design's fitted points: the squared
// difference between `with` and `without` (same seeds) in units of the noise a calibration
// of the twin sees, built from `se` (per point: the run-to-run standard error of a mean of
// def.replicates runs, estimated independently of this pair) and `model_se` (the model's part,
// loop_model_se), less the paired runs' own noise (calibrate/twin.cpp says why). Below 0 where
// the noise outweighs the signal.
double planted_noncentrality(const DataFile& design, const Prediction& with, const Prediction& without,
                             const std::vector<double>& se, const std::vector<double>& model_se);

// Per point, the model's standard error on the fit scale at the design's model replicates,
// from `se` (a mean of def.replicates runs): as one raw grid node has it, ...
std::vector<double> raw_model_se(const DataFile& design, const TwinDef& def, const std::vector<double>& se);
// ... and as the loop sees it: the response surface through the grid's nodes around node
// `near` (fit.hpp, surface_around), built from `predictions` (def.replicates runs each).
std::vector<double> loop_model_se(const DataFile& design, const TwinDef& def, const std::vector<ParameterSet>& nodes,
                                  const std::vector<Prediction>& predictions, std::size_t near);

// The planted values (drawn from def.seed), without running anything.
TwinTruth draw_twin(const DataFile& design, const TwinDef& def);

// Run the design with the planted values and write the twin data file and its truth.
TwinTruth make_twin(const DataFile& design, const TwinDef& def, Evaluator& evaluator,
                    const std::filesystem::path& data_out, const std::filesystem::path& truth_out);

}  // namespace gapflow

// Step 3 of the loop (calibrate/calibration.hpp): the catalogue's candidates scored against a state's residual.
// Each visible candidate's signature, whitened by the state's total sigma, gets a score test against the
// fitted points' residual with what the fit already moves projected out (the free parameters, the effects
// added, and the free parameters' measurements as rows of their own: a measured parameter cannot move freely
// to mimic an effect); a size the effect's range cannot take in the score's direction scores 0. Then the
// Bonferroni-adjusted p's, the best, its rivals (the candidates these data cannot rank below it at alpha)
// and the groups whose whitened signatures these data cannot tell apart (|cos| above def.group_cosine).
// The statistics themselves are calibrate/attribution.hpp's.
#pragma once

#include "calibrate/calibration.hpp"
#include "calibrate/fit.hpp"

#include <vector>

namespace gapflow {

Round score_candidates(const DataFile& data, const CalibrationDef& def, std::vector<Candidate> cands,
                       const ModelState& state, const Surface& surface);

}  // namespace gapflow

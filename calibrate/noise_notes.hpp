// What the baseline's noise tells a reader of the calibration's log: the model's share of the
// residual's variance (and the replicates that would lower it) and the correlation of points that
// measure different observables on the same runs. Text for the log only; no decision reads it.
#pragma once

#include "calibrate/data_file.hpp"
#include "calibrate/fit.hpp"

#include <string>
#include <vector>

namespace gapflow {

// Per pair of observables measured on the same runs: their noise's correlation on the baseline
// nodes' replicates, one line each (e.g. "j_paper / clog_share: rho = +0.12 over 840 replicate pairs").
std::vector<std::string> shared_run_correlations(const DataFile& data, const BaselineFit& base);

// The model's share of the variance at the baseline (deviance.hpp, model_noise_share) in words, with the
// least number of replicates that would bring it to 20 % where it is above (a lower bound).
std::string model_noise_text(double share, int model_replicates);

}  // namespace gapflow

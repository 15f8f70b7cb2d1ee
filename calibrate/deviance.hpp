// How far the model is from the data, on the fit scale: each point's total standard error (data and
// model in quadrature), the whitened residuals, chi^2 over fitted or held-out points, the fits'
// deviance, and the independent measurements of free parameters counted as data. Every fit and test
// of the loop (calibrate/fit.hpp, error_measures.hpp, candidate_scores.hpp) reads the data through these.
#pragma once

#include "calibrate/data_file.hpp"
#include "calibrate/evaluator.hpp"

#include <Eigen/Dense>

#include <cstddef>
#include <string>
#include <vector>

namespace gapflow {

// The total standard error of point i's residual on the fit scale (data and model
// added in quadrature; the data's value there: DataFile::fit_value).
double total_sigma(const DataFile& data, const Prediction& p, std::size_t i);
// Data minus model over total_sigma, on the fit scale, at every point; an invalid model point
// counts as 10 sigma (as in chi2_of and the fits' deviance).
std::vector<double> whitened_residual(const DataFile& data, const Prediction& p);
// The model's share of the residual's variance, se_model^2 / (se_data^2 + se_model^2), median over
// the fitted points where the model is valid (NaN with none). Every test of the loop weighs the
// residual by both: where the model's share is large, its own noise, not the data's, limits what
// the loop can tell (blind pass 15's twins, data of 10 runs: median 31 % at 6 model replicates, 23 %
// at 12). Lowering it did not by itself identify more: 15 of 18 on fresh twins at 12 (blind pass 17;
// calibrate/README.md, "The model's own noise is part of every test").
double model_noise_share(const DataFile& data, const Prediction& p);
// chi^2 over the fitted (or held-out) points; an invalid model point counts as 10 sigma.
double chi2_of(const DataFile& data, const Prediction& p, bool held_out = false);
// The fits' objective: -2 ln(Gaussian likelihood) over the fitted points up to a constant,
// chi^2 + sum 2 ln(sigma_i). The surface's sigma_i depends on the parameters (an effect's
// response carries the noise of its finite differences, growing beyond the measured sizes),
// and chi^2 alone falls where that noise rises: minimised, it is drawn to wherever the model
// is least certain (tests/test_calibration_fit.cpp). BIC is taken on it too.
// With `params`, the independent measurements of free parameters (FreeParameter::measured) are
// added: they are data too, fitted like the points.
double deviance_of(const DataFile& data, const Prediction& p, const ParameterSet& params);

// The measurements' share of chi^2: sum over measured free parameters of ((value - measured)/se)^2.
double measurement_chi2(const DataFile& data, const ParameterSet& params);
// chi^2 of everything fitted: the fitted points (chi2_of) and the measurements at `params`.
double fitted_chi2(const DataFile& data, const Prediction& p, const ParameterSet& params);
// How many free parameters carry a measurement (each one more fitted datum).
int measured_count(const DataFile& data);
// The measurements' whitened residuals (measured - value)/se and, per measured parameter, its row
// of the whitened sensitivities to `columns` keys: 1/se in its own column, 0 elsewhere (a
// measurement sees its parameter only, no effect). Appended below the fitted points' rows.
struct MeasurementRows {
  Eigen::VectorXd residual;   // one per measured free parameter
  Eigen::MatrixXd sensitivity;  // [measured][columns]
};
MeasurementRows measurement_rows(const DataFile& data, const ParameterSet& params, const std::vector<std::string>& columns);

}  // namespace gapflow

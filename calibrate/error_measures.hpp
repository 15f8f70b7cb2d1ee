// The errors before and after: what calibrate reports of a state on its fitted and held-out points,
// and the held-out tests of the keep rule and of the verdict (calibrate/decisions.hpp, rules 2 and 3).
#pragma once

#include "calibrate/calibration.hpp"
#include "calibrate/evaluator.hpp"
#include "calibrate/fit.hpp"

#include <string>
#include <vector>

namespace gapflow {

// RMSE, RMS of the whitened residual and chi^2 over the fitted (held_out false) or held-out points.
// `params` are the parameters behind `p`: on the fitted points the free parameters' measurements
// join the chi^2 (one degree of freedom each), not the RMSE or the RMS (those are the points').
ErrorMeasures error_measures(const DataFile& data, const Prediction& p, const ParameterSet& params, bool held_out,
                             int fitted_parameters);

// A state's residuals, errors and BIC at `params` with prediction `p`.
ModelState make_state(const DataFile& data, const ParameterSet& params, const Prediction& p, int fitted_parameters);

struct HeldOutCheck {
  int n = 0;                     // held-out points
  double before = 0, after = 0;  // their chi^2, direct simulation on the keep test's own seeds
};

// The keep test's held-out comparison of two parameter sets (decisions.hpp, rule 2).
HeldOutCheck held_out_check(const DataFile& data, const CalibrationDef& def, Evaluator& ev, const ParameterSet& before,
                            const ParameterSet& after);

// The surface's sensitivities to every fitted parameter (free ones and added effects) at `params`:
// central differences over 1e-3 of each parameter's range. A parameter the fit left at an end of
// its range (twin-3d's rolling contact at 1): left out (`leave_out`: the held-out test, whose
// variance must not widen along a direction the fit cannot move in), or a one-sided difference into
// the range (`one_sided`: the form check, which must project out every direction the fit used).
enum class AtRangeEnd { leave_out, one_sided };
struct SurfaceSlopes {
  std::vector<std::string> keys;
  std::vector<std::vector<double>> slope;  // [key][point], fit scale per key unit
};
SurfaceSlopes surface_slopes(const DataFile& data, const Surface& surface, const ParameterSet& params,
                             AtRangeEnd at_end = AtRangeEnd::leave_out);

// The fitted points' whitened residual at `state` and their whitened sensitivities (`slopes`), with
// the free parameters' measurements as rows of their own below: fitted data, they narrow what the
// fit can move. A point without a value (the model's or the surface's) is a row of zeros.
struct FittedRows {
  std::vector<std::size_t> points;  // data index of each point row (the measurement rows follow)
  Eigen::VectorXd r;
  Eigen::MatrixXd X;                // [row][key of slopes]
  int informative = 0;              // rows with a value: points with one, and the measurements
};
FittedRows fitted_rows(const DataFile& data, const Surface& surface, const ModelState& state,
                       const SurfaceSlopes& slopes);

// The verdict's held-out chi^2 on fresh seeds with the fitted parameters' uncertainty (rule 3).
ChiSquare held_out_fit_aware(const DataFile& data, const Surface& surface, const ModelState& after,
                             const Prediction& fresh);

}  // namespace gapflow

// The errors before and after (calibration.hpp ErrorMeasures, ModelState): whitened residuals, RMSE,
// chi^2 with its p on fitted and held-out points, and the two held-out tests, the keep test's (direct
// simulation of two parameter sets) and the verdict's (the fitted parameters' uncertainty carried).
#include "calibrate/error_measures.hpp"

#include "calibrate/attribution.hpp"
#include "calibrate/fit.hpp"
#include "common/statistics.hpp"

#include <cmath>
#include <string>
#include <vector>

namespace gapflow {

HeldOutCheck held_out_check(const DataFile& data, const CalibrationDef& def, Evaluator& ev, const ParameterSet& before,
                            const ParameterSet& after) {
  HeldOutCheck c;
  c.n = static_cast<int>(data.points.size() - data.fitted_count());
  if (c.n == 0) return c;
  // Only the held-out points, at keep_test_replicate_factor x the replicates: a parameter change parts
  // the trajectories within a few collisions, so the two sets' runs are nearly independent even on
  // common seeds, and at the file's replicate count their noise was as large as the data's own
  // (blind study pass 4, commit 8b8781f: a planted size scatter with BIC 55.6 -> 34.5 was rejected
  // for 29.5 -> 35.2 on 12 points).
  const std::vector<Prediction> p = ev.evaluate({before, after}, data.seed + def.decision_seed_offset,
                                                data.model_replicates * def.keep_test_replicate_factor,
                                                data.held_out_flags());
  c.before = chi2_of(data, p[0], true);
  c.after = chi2_of(data, p[1], true);
  return c;
}

// `params` are the parameters behind `p`: on the fitted points the free parameters' measurements
// join the chi^2 (one degree of freedom each), not the RMSE or the RMS (those are the points').
ErrorMeasures error_measures(const DataFile& data, const Prediction& p, const ParameterSet& params, bool held_out,
                      int fitted_parameters) {
  ErrorMeasures m;
  const std::vector<double> w = whitened_residual(data, p);
  std::vector<double> picked;
  double sq = 0;
  for (std::size_t i = 0; i < data.points.size(); ++i) {
    if (data.points[i].held_out != held_out) continue;
    picked.push_back(w[i]);
    if (!p.valid[i]) {
      ++m.invalid;
      continue;
    }
    const double e = data.fit_value(i) - p.fit[i];
    sq += e * e;
  }
  m.n = static_cast<int>(picked.size());
  if (m.n == 0) return m;
  const int valid = m.n - m.invalid;
  m.rmse = valid > 0 ? std::sqrt(sq / valid) : kNaN;
  const Eigen::VectorXd v = Eigen::Map<const Eigen::VectorXd>(picked.data(), m.n);
  m.rms_whitened = std::sqrt(v.squaredNorm() / m.n);
  if (held_out) {
    m.chi = chi_square_of(v, 0);
    return m;
  }
  const Eigen::VectorXd meas = measurement_rows(data, params, {}).residual;
  Eigen::VectorXd all(v.size() + meas.size());
  all << v, meas;
  m.chi = chi_square_of(all, fitted_parameters);
  return m;
}

ModelState make_state(const DataFile& data, const ParameterSet& params, const Prediction& p, int fitted_parameters) {
  ModelState s;
  s.params = params;
  s.prediction = p;
  s.whitened = whitened_residual(data, p);
  s.fitted = error_measures(data, p, params, false, fitted_parameters);
  s.held_out = error_measures(data, p, params, true, fitted_parameters);
  // The fits' objective, not chi^2 (fit.hpp); the measurements are data of the fit.
  s.bic = bic(deviance_of(data, p, params), fitted_parameters, s.fitted.n + measured_count(data));
  return s;
}

SurfaceSlopes surface_slopes(const DataFile& data, const Surface& surface, const ParameterSet& params) {
  SurfaceSlopes out;
  auto consider = [&](const std::string& key, double fallback, double lo, double hi) {
    const double at = params.get(key, fallback), h = 1e-3 * (hi - lo);
    if (at - h <= lo || at + h >= hi) return;
    const Prediction up = surface.predict_fit(params.with(key, at + h));
    const Prediction dn = surface.predict_fit(params.with(key, at - h));
    std::vector<double> d;
    for (std::size_t i = 0; i < data.points.size(); ++i) d.push_back((up.fit[i] - dn.fit[i]) / (2 * h));
    out.keys.push_back(key);
    out.slope.push_back(std::move(d));
  };
  for (const FreeParameter& f : data.free) consider(f.key, 0.5 * (f.lo + f.hi), f.lo, f.hi);
  for (const EffectTerm& e : surface.effects) consider(e.key, e.neutral, e.lo, e.hi);
  return out;
}

// The final state's held-out chi^2 on fresh seeds, with the fitted parameters' (free and added
// effects') uncertainty carried to the held-out points (held_out_chi_square), the sensitivities
// surface_slopes'.
ChiSquare held_out_fit_aware(const DataFile& data, const Surface& surface, const ModelState& after,
                             const Prediction& fresh) {
  const SurfaceSlopes slopes = surface_slopes(data, surface, after.params);
  const std::vector<std::vector<double>>& slope = slopes.slope;
  std::vector<std::size_t> fitted, held;
  for (std::size_t i = 0; i < data.points.size(); ++i) (data.points[i].held_out ? held : fitted).push_back(i);
  const auto k = static_cast<Eigen::Index>(slopes.keys.size());
  Eigen::MatrixXd X(static_cast<Eigen::Index>(fitted.size()), k), G(static_cast<Eigen::Index>(held.size()), k);
  Eigen::VectorXd r(static_cast<Eigen::Index>(held.size()));
  const std::vector<double> w = whitened_residual(data, fresh);
  for (Eigen::Index j = 0; j < k; ++j) {
    const std::vector<double>& d = slope[static_cast<std::size_t>(j)];
    for (std::size_t a = 0; a < fitted.size(); ++a) {
      const std::size_t i = fitted[a];
      X(static_cast<Eigen::Index>(a), j) =
          after.prediction.valid[i] && surface.valid[i] ? d[i] / total_sigma(data, after.prediction, i) : 0.0;
    }
    for (std::size_t b = 0; b < held.size(); ++b) {
      const std::size_t i = held[b];
      G(static_cast<Eigen::Index>(b), j) = fresh.valid[i] && surface.valid[i] ? d[i] / total_sigma(data, fresh, i) : 0.0;
    }
  }
  for (std::size_t b = 0; b < held.size(); ++b) r(static_cast<Eigen::Index>(b)) = w[held[b]];
  // The measurements are fitted data: they narrow the fitted parameters' uncertainty.
  const MeasurementRows meas = measurement_rows(data, after.params, slopes.keys);
  Eigen::MatrixXd Xm(X.rows() + meas.sensitivity.rows(), k);
  Xm << X, meas.sensitivity;
  return held_out_chi_square(r, G, Xm);
}

}  // namespace gapflow

// The errors before and after (calibration.hpp ErrorMeasures, ModelState): whitened residuals, RMSE,
// chi^2 with its p on fitted and held-out points, and the two held-out tests, the keep test's (direct
// simulation of two parameter sets) and the verdict's (the fitted parameters' uncertainty carried).
#include "calibrate/error_measures.hpp"

#include "calibrate/attribution.hpp"
#include "calibrate/fit.hpp"
#include "common/statistics.hpp"

#include <algorithm>
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
  // The fits' objective, not chi^2 (deviance.hpp); the measurements are data of the fit.
  s.bic = bic(deviance_of(data, p, params), fitted_parameters, s.fitted.n + measured_count(data));
  return s;
}

SurfaceSlopes surface_slopes(const DataFile& data, const Surface& surface, const ParameterSet& params,
                             AtRangeEnd at_end) {
  SurfaceSlopes out;
  auto consider = [&](const std::string& key, double fallback, double lo, double hi) {
    const double at = params.get(key, fallback), h = 1e-3 * (hi - lo);
    const bool inside = at - h > lo && at + h < hi;
    if (!inside && at_end == AtRangeEnd::leave_out) return;
    // Inside: central; at an end: one-sided into the range.
    const double up_at = inside || at - h <= lo ? at + h : at, dn_at = inside || at + h >= hi ? at - h : at;
    const Prediction up = surface.predict_fit(params.with(key, std::min(up_at, hi)));
    const Prediction dn = surface.predict_fit(params.with(key, std::max(dn_at, lo)));
    const double width = inside ? 2 * h : std::min(up_at, hi) - std::max(dn_at, lo);  // 2h: as before one_sided
    if (!(width > 0)) return;
    std::vector<double> d;
    for (std::size_t i = 0; i < data.points.size(); ++i) d.push_back((up.fit[i] - dn.fit[i]) / width);
    out.keys.push_back(key);
    out.slope.push_back(std::move(d));
  };
  for (const FreeParameter& f : data.free) consider(f.key, 0.5 * (f.lo + f.hi), f.lo, f.hi);
  for (const EffectTerm& e : surface.effects) consider(e.key, e.neutral, e.lo, e.hi);
  return out;
}

FittedRows fitted_rows(const DataFile& data, const Surface& surface, const ModelState& state,
                       const SurfaceSlopes& slopes) {
  FittedRows f;
  for (std::size_t i = 0; i < data.points.size(); ++i)
    if (!data.points[i].held_out) f.points.push_back(i);
  const MeasurementRows meas = measurement_rows(data, state.params, slopes.keys);
  const auto n = static_cast<Eigen::Index>(f.points.size()), rows = n + meas.residual.size();
  const auto k = static_cast<Eigen::Index>(slopes.keys.size());
  f.r = Eigen::VectorXd::Zero(rows);
  f.X = Eigen::MatrixXd::Zero(rows, k);
  for (Eigen::Index a = 0; a < n; ++a) {
    const std::size_t i = f.points[static_cast<std::size_t>(a)];
    if (!state.prediction.valid[i] || !surface.valid[i]) continue;
    ++f.informative;
    f.r(a) = state.whitened[i];
    const double sigma = total_sigma(data, state.prediction, i);
    for (Eigen::Index j = 0; j < k; ++j) f.X(a, j) = slopes.slope[static_cast<std::size_t>(j)][i] / sigma;
  }
  f.r.tail(meas.residual.size()) = meas.residual;
  f.X.bottomRows(meas.residual.size()) = meas.sensitivity;
  f.informative += static_cast<int>(meas.residual.size());
  return f;
}

// The final state's held-out chi^2 on fresh seeds, with the fitted parameters' (free and added
// effects') uncertainty carried to the held-out points (held_out_chi_square), the sensitivities
// surface_slopes' (a parameter at an end of its range left out).
ChiSquare held_out_fit_aware(const DataFile& data, const Surface& surface, const ModelState& after,
                             const Prediction& fresh) {
  const SurfaceSlopes slopes = surface_slopes(data, surface, after.params);
  std::vector<std::size_t> held;
  for (std::size_t i = 0; i < data.points.size(); ++i)
    if (data.points[i].held_out) held.push_back(i);
  const auto k = static_cast<Eigen::Index>(slopes.keys.size());
  Eigen::MatrixXd G(static_cast<Eigen::Index>(held.size()), k);
  Eigen::VectorXd r(static_cast<Eigen::Index>(held.size()));
  const std::vector<double> w = whitened_residual(data, fresh);
  for (std::size_t b = 0; b < held.size(); ++b) {
    const std::size_t i = held[b];
    r(static_cast<Eigen::Index>(b)) = w[i];
    for (Eigen::Index j = 0; j < k; ++j)
      G(static_cast<Eigen::Index>(b), j) =
          fresh.valid[i] && surface.valid[i] ? slopes.slope[static_cast<std::size_t>(j)][i] / total_sigma(data, fresh, i) : 0.0;
  }
  // The fitted points' sensitivities and the measurements' rows: what the fit's uncertainty is made of.
  return held_out_chi_square(r, G, fitted_rows(data, surface, after, slopes).X);
}

}  // namespace gapflow

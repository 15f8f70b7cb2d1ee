#include "calibrate/candidate_scores.hpp"

#include "calibrate/attribution.hpp"
#include "calibrate/deviance.hpp"
#include "calibrate/effect_catalogue.hpp"
#include "common/statistics.hpp"

#include <algorithm>

namespace gapflow {

namespace {

// The fitted points of a per-point vector, whitened by the state's total sigma.
Eigen::VectorXd fitted_whitened(const DataFile& data, const Prediction& at, const std::vector<double>& per_point) {
  std::vector<double> v;
  for (std::size_t i = 0; i < data.points.size(); ++i)
    if (!data.points[i].held_out) v.push_back(at.valid[i] ? per_point[i] / total_sigma(data, at, i) : 0.0);
  return Eigen::Map<const Eigen::VectorXd>(v.data(), static_cast<Eigen::Index>(v.size()));
}

}  // namespace

Round score_candidates(const DataFile& data, const CalibrationDef& def, std::vector<Candidate> cands,
                       const ModelState& state, const Surface& surface) {
  Round round;
  const Prediction& at = state.prediction;
  std::vector<double> r;
  for (std::size_t i = 0; i < data.points.size(); ++i)
    if (!data.points[i].held_out) r.push_back(state.whitened[i]);
  // The free parameters' measurements are rows of their own below the points: a measured
  // parameter cannot move freely to mimic an effect, so less of a signature is projected out.
  std::vector<std::string> columns = surface.keys;
  for (const EffectTerm& t : surface.effects) columns.push_back(t.key);
  const MeasurementRows meas = measurement_rows(data, state.params, columns);
  const auto n_points = static_cast<Eigen::Index>(r.size()), n_rows = n_points + meas.residual.size();
  Eigen::VectorXd rv(n_rows);
  rv << Eigen::Map<const Eigen::VectorXd>(r.data(), n_points), meas.residual;
  // X: what the fit already moves: the free parameters and the effects added.
  Eigen::MatrixXd X(n_rows, static_cast<Eigen::Index>(columns.size()));
  X.bottomRows(meas.residual.size()) = meas.sensitivity;
  Eigen::Index col = 0;
  for (std::size_t k = 0; k < surface.keys.size(); ++k)
    X.col(col++).head(n_points) = fitted_whitened(data, at, surface.derivative(state.params, k));
  for (const EffectTerm& t : surface.effects) X.col(col++).head(n_points) = fitted_whitened(data, at, t.slope);
  std::vector<Eigen::VectorXd> visible_u;
  std::vector<std::size_t> visible_index;
  for (std::size_t c = 0; c < cands.size(); ++c) {
    if (!cands[c].visible) continue;
    Eigen::VectorXd u = Eigen::VectorXd::Zero(n_rows);  // an effect does not move a measurement
    u.head(n_points) = fitted_whitened(data, at, cands[c].signature);
    cands[c].score = score_signature(rv, X, u);
    const EffectDef& e = *find_effect(cands[c].effect);
    cands[c].direction_possible =
        size_direction_possible(cands[c].score.estimate, cands[c].neutral, e.lo, e.hi, cands[c].step);
    if (!cands[c].direction_possible) cands[c].score.statistic = 0, cands[c].score.p = 1;
    visible_u.push_back(u);
    visible_index.push_back(c);
  }
  const double n_tests = static_cast<double>(std::max<std::size_t>(1, visible_index.size()));
  double best_stat = -1;
  for (std::size_t c : visible_index) {
    cands[c].p_adjusted = std::min(1.0, cands[c].score.p * n_tests);
    if (cands[c].score.statistic > best_stat) best_stat = cands[c].score.statistic, round.best = cands[c].effect;
  }
  // Rivals: candidates these data cannot rank below the best (calibrate/attribution.hpp).
  std::vector<double> visible_scores;
  for (std::size_t c : visible_index) visible_scores.push_back(cands[c].score.statistic);
  for (int m : rivals_of(visible_scores, chi_square_quantile(1 - def.alpha, 1)))
    round.rivals.push_back(cands[visible_index[static_cast<std::size_t>(m)]].effect);
  const auto groups = indistinguishable_groups(visible_u, X, def.group_cosine);
  for (std::size_t g = 0; g < groups.size(); ++g) {
    for (int m : groups[g]) cands[visible_index[static_cast<std::size_t>(m)]].group = static_cast<int>(g);
    if (groups[g].size() < 2) continue;
    std::vector<std::string> names;
    for (int m : groups[g]) names.push_back(cands[visible_index[static_cast<std::size_t>(m)]].effect);
    round.groups.push_back(names);
  }
  round.candidates = std::move(cands);
  return round;
}

}  // namespace gapflow

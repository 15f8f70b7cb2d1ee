#include "calibrate/form_check.hpp"

#include "calibrate/attribution.hpp"
#include "calibrate/calibration.hpp"
#include "calibrate/error_measures.hpp"
#include "calibrate/fit.hpp"
#include "common/statistics.hpp"

#include <algorithm>
#include <cmath>
#include <map>

namespace gapflow {
namespace {

// The fitted points' whitened residual and sensitivities at the final state, with the free
// parameters' measurements as rows of their own below (they are fitted data: score_round's X).
struct FittedRows {
  std::vector<std::size_t> points;  // data index of each point row
  Eigen::VectorXd r;
  Eigen::MatrixXd X;                // [row][key of slopes]
};

FittedRows fitted_rows(const DataFile& data, const Surface& surface, const ModelState& after,
                       const SurfaceSlopes& slopes) {
  FittedRows f;
  for (std::size_t i = 0; i < data.points.size(); ++i)
    if (!data.points[i].held_out) f.points.push_back(i);
  const MeasurementRows meas = measurement_rows(data, after.params, slopes.keys);
  const auto n = static_cast<Eigen::Index>(f.points.size()), rows = n + meas.residual.size();
  const auto k = static_cast<Eigen::Index>(slopes.keys.size());
  f.r = Eigen::VectorXd::Zero(rows);
  f.X = Eigen::MatrixXd::Zero(rows, k);
  for (Eigen::Index a = 0; a < n; ++a) {
    const std::size_t i = f.points[static_cast<std::size_t>(a)];
    if (!after.prediction.valid[i] || !surface.valid[i]) continue;  // no value: no information on a size
    f.r(a) = after.whitened[i];
    const double sigma = total_sigma(data, after.prediction, i);
    for (Eigen::Index j = 0; j < k; ++j) f.X(a, j) = slopes.slope[static_cast<std::size_t>(j)][i] / sigma;
  }
  f.r.tail(meas.residual.size()) = meas.residual;
  f.X.bottomRows(meas.residual.size()) = meas.sensitivity;
  return f;
}

// The partitions a size may differ over: each design column, and the observable where the fitted
// points measure more than one. level[p][row]: the level's label of each point row.
std::vector<std::pair<std::string, std::vector<std::string>>> partitions(const DataFile& data,
                                                                         const std::vector<std::size_t>& points) {
  std::vector<std::pair<std::string, std::vector<std::string>>> out;
  for (std::size_t c = 0; c < data.design.size(); ++c) {
    std::vector<std::string> level;
    for (std::size_t i : points) level.push_back(data.points[i].design[c]);
    out.emplace_back(data.design[c].column, std::move(level));
  }
  std::vector<std::string> observed;
  for (std::size_t i : points) observed.push_back(to_string(data.points[i].observable));
  if (std::any_of(observed.begin(), observed.end(), [&](const std::string& o) { return o != observed.front(); }))
    out.emplace_back("observable", std::move(observed));
  return out;
}

// One column per level the effect moves at min_points_per_level points or more: the effect's
// sensitivity u at that level's rows, 0 elsewhere. Fewer than two such levels: no columns.
Eigen::MatrixXd split_by_level(const Eigen::VectorXd& u, const std::vector<std::string>& level, int min_points) {
  std::map<std::string, std::vector<Eigen::Index>> rows;
  for (std::size_t a = 0; a < level.size(); ++a)
    if (u(static_cast<Eigen::Index>(a)) != 0) rows[level[a]].push_back(static_cast<Eigen::Index>(a));
  std::vector<const std::vector<Eigen::Index>*> kept;
  for (const auto& [name, at] : rows)
    if (static_cast<int>(at.size()) >= min_points) kept.push_back(&at);
  if (kept.size() < 2) return Eigen::MatrixXd(u.size(), 0);
  Eigen::MatrixXd U = Eigen::MatrixXd::Zero(u.size(), static_cast<Eigen::Index>(kept.size()));
  for (std::size_t l = 0; l < kept.size(); ++l)
    for (Eigen::Index a : *kept[l]) U(a, static_cast<Eigen::Index>(l)) = u(a);
  return U;
}

}  // namespace

std::vector<FormCheck> form_checks(const DataFile& data, const Surface& surface, const ModelState& after,
                                   const FormCheckDef& def) {
  std::vector<FormCheck> checks;
  if (surface.effects.empty()) return checks;
  const SurfaceSlopes slopes = surface_slopes(data, surface, after.params);
  const FittedRows f = fitted_rows(data, surface, after, slopes);
  const auto parts = partitions(data, f.points);
  for (const EffectTerm& e : surface.effects) {
    const auto at = std::find(slopes.keys.begin(), slopes.keys.end(), e.key);
    if (at == slopes.keys.end()) continue;  // at an end of its range
    const Eigen::VectorXd u = f.X.col(at - slopes.keys.begin());
    for (const auto& [column, level] : parts) {
      std::vector<std::string> rows_level = level;
      rows_level.resize(static_cast<std::size_t>(u.size()));  // measurement rows: no level (u is 0 there)
      const Eigen::MatrixXd U = split_by_level(u, rows_level, def.min_points_per_level);
      const BlockScore b = score_block(f.r, f.X, U);
      if (b.dof == 0) continue;
      FormCheck c;
      c.effect = e.effect;
      c.column = column;
      c.levels = static_cast<int>(U.cols());
      c.statistic = b.statistic;
      c.dof = b.dof;
      const int rest_dof = after.fitted.chi.dof - b.dof;
      if (rest_dof > 0) c.scale = std::max(1.0, (after.fitted.chi.chi2 - b.statistic) / rest_dof);
      c.p = 1 - chi_square_cdf(c.statistic / c.scale, c.dof);
      checks.push_back(c);
    }
  }
  for (FormCheck& c : checks) c.p_adjusted = std::min(1.0, c.p * static_cast<double>(checks.size()));
  return checks;
}

bool form_differs(const std::vector<FormCheck>& checks, double alpha) {
  return std::any_of(checks.begin(), checks.end(), [&](const FormCheck& c) { return c.p_adjusted < alpha; });
}

}  // namespace gapflow

#include "calibrate/form_check.hpp"

#include "calibrate/attribution.hpp"
#include "calibrate/calibration.hpp"
#include "calibrate/detectability.hpp"
#include "calibrate/effect_catalogue.hpp"
#include "calibrate/error_measures.hpp"
#include "calibrate/fit.hpp"
#include "common/statistics.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <map>
#include <numbers>

namespace gapflow {
namespace {

constexpr double kRoundingShare = 1e-9;  // of a squared norm: below it, what is left is rounding

constexpr const char* kInclineKey = "plane.incline_deg";

// A partition a size may differ over: a design column (with the scenario key it sets), or the
// observable; a level's label per point row.
struct Partition {
  std::string column;
  std::string key;  // "" for the observable
  std::vector<std::string> level;
};

// Each design column, and the observable where the fitted points measure more than one. Design
// values are TOML literals as the loader normalised them (number_text: 4.5 and 4.50 are one level).
std::vector<Partition> partitions(const DataFile& data, const std::vector<std::size_t>& points) {
  std::vector<Partition> out;
  for (std::size_t c = 0; c < data.design.size(); ++c) {
    Partition p{data.design[c].column, data.design[c].key, {}};
    for (std::size_t i : points) p.level.push_back(data.points[i].design[c]);
    out.push_back(std::move(p));
  }
  std::vector<std::string> observed;
  for (std::size_t i : points) observed.push_back(to_string(data.points[i].observable));
  if (std::any_of(observed.begin(), observed.end(), [&](const std::string& o) { return o != observed.front(); }))
    out.push_back({"observable", "", std::move(observed)});
  return out;
}

// The sizes another law in the speed asks along this partition, where it is the incline (in
// degrees: the key's own unit) and the effect has a law in the speed; empty elsewhere.
LawSize law_along(const Partition& part, const EffectDef* effect, const DataFile& data, double exponent) {
  if (effect == nullptr || !effect->speed_law || part.key != kInclineKey) return {};
  const auto column = std::find_if(data.design.begin(), data.design.end(),
                                   [&](const DesignColumn& d) { return d.column == part.column; });
  if (column == data.design.end() || column->in_diameters) return {};
  return [exponent](const std::string& level) { return speed_law_size(level, exponent); };
}

// Each kept level's place on a straight trend, 0 at the lowest level and 1 at the highest: by the
// level's value where every label is a number; where two levels are not, either order (the F test
// does not see the trend's sign); empty where more than two are not (no order to trend along) or
// all values are equal.
std::vector<double> trend_of(const std::vector<std::string>& labels) {
  std::vector<double> x;
  for (const std::string& label : labels) {
    char* end = nullptr;
    const double v = std::strtod(label.c_str(), &end);
    if (label.empty() || *end != '\0' || !std::isfinite(v)) {
      x.clear();
      break;
    }
    x.push_back(v);
  }
  if (x.empty() && labels.size() == 2) return {0.0, 1.0};
  if (x.empty()) return {};
  const auto [lo, hi] = std::minmax_element(x.begin(), x.end());
  if (!(*hi > *lo)) return {};
  const double low = *lo, width = *hi - *lo;
  for (double& v : x) v = (v - low) / width;
  return x;
}

// |P U c|^2: the noncentrality a trend c (0 at the lowest level, 1 at the highest) adds per unit
// spread and key unit^2 of departure. NaN without an order; 0 where the fitted directions take the
// trend in (what is left of it no more than rounding, as score_block judges a direction).
double trend_noncentrality(const Eigen::MatrixXd& P, const Eigen::MatrixXd& U, const std::vector<double>& trend) {
  if (trend.empty()) return std::numeric_limits<double>::quiet_NaN();
  const Eigen::VectorXd shift = U * Eigen::Map<const Eigen::VectorXd>(trend.data(), U.cols());
  const double left = (P * shift).squaredNorm();
  return left > kRoundingShare * shift.squaredNorm() ? left : 0.0;
}

// The other law's sizes, against the one size the fit would give them. Under that law the data
// hold the effect at a size k s(level) at every row; the fit, linear, reads it as the one departure
// k c, c the coefficient on u of the least-squares fit of those sizes (U_all s, every level's rows,
// the untested ones too) on the fitted directions X: a mean of s weighted by each row's whitened
// sensitivity, not s's plain mean. A fitted departure d then stands for k = d / c, and the check
// sees lambda = k^2 |P U s|^2 (the kept levels' part; P takes out every fitted direction):
// law_noncentrality = |P U s|^2 / c^2 per unit^2 of fitted departure, law_spread = (max - min of s
// over the kept levels) / c. Nothing where a moved row's level has no size or u is no column of X;
// NaN where c is not positive (the fit would not read the law as this effect at all). Nothing, too,
// where the untested levels' rows keep a part of the law's sizes that P leaves (two or more such
// levels asking different sizes: Xc holds only their sum): that part would fall partly outside the
// tested directions, into the rest the F divides by, and the central-F power would overstate what
// the check sees (found by a second reading: stated 0.60, flagged 0.07 with one-point 3 and 20 deg
// levels). One untested level, or several asking one size, leave nothing: it is in Xc.
void set_law(FormCheck& c, const Eigen::MatrixXd& X, const Eigen::VectorXd& u, const std::vector<std::string>& level,
             const Eigen::MatrixXd& P, const Eigen::MatrixXd& U, const std::vector<std::string>& kept_labels,
             const LawSize& law_size) {
  Eigen::Index column = -1;
  for (Eigen::Index j = 0; j < X.cols() && column < 0; ++j)
    if ((X.col(j) - u).squaredNorm() == 0) column = j;
  if (column < 0) return;
  Eigen::VectorXd all_sizes = Eigen::VectorXd::Zero(u.size());  // U_all s
  for (std::size_t a = 0; a < level.size() && a < static_cast<std::size_t>(u.size()); ++a) {
    const auto row = static_cast<Eigen::Index>(a);
    if (u(row) == 0) continue;
    const double size = law_size(level[a]);
    if (!std::isfinite(size)) return;
    all_sizes(row) = u(row) * size;
  }
  Eigen::VectorXd kept(static_cast<Eigen::Index>(kept_labels.size()));
  for (std::size_t l = 0; l < kept_labels.size(); ++l) kept(static_cast<Eigen::Index>(l)) = law_size(kept_labels[l]);
  const double fitted = X.colPivHouseholderQr().solve(all_sizes)(column);
  if (!(fitted > 0)) return;
  const Eigen::VectorXd shift = U * kept;
  if ((P * (all_sizes - shift)).squaredNorm() > kRoundingShare * all_sizes.squaredNorm()) return;
  c.law_spread = (kept.maxCoeff() - kept.minCoeff()) / fitted;
  const double left = (P * shift).squaredNorm();
  c.law_noncentrality = left > kRoundingShare * shift.squaredNorm() ? left / (fitted * fitted) : 0.0;
}

}  // namespace

FormCheck check_split(const Eigen::VectorXd& r, const Eigen::MatrixXd& X, const Eigen::VectorXd& u,
                      const std::vector<std::string>& level, int informative_rows, const FormCheckDef& def,
                      const LawSize& law_size) {
  FormCheck c;
  // The rows of each level the effect moves; rows past `level` (the measurements') have none.
  std::map<std::string, std::vector<Eigen::Index>> rows;
  for (std::size_t a = 0; a < level.size() && a < static_cast<std::size_t>(u.size()); ++a)
    if (u(static_cast<Eigen::Index>(a)) != 0) rows[level[a]].push_back(static_cast<Eigen::Index>(a));
  std::vector<const std::vector<Eigen::Index>*> kept;
  std::vector<std::string> kept_labels;
  for (const auto& [name, at] : rows)
    if (static_cast<int>(at.size()) >= def.min_points_per_level) {
      kept.push_back(&at);
      kept_labels.push_back(name);
    }
  if (kept.size() < 2) return c;
  Eigen::MatrixXd U = Eigen::MatrixXd::Zero(u.size(), static_cast<Eigen::Index>(kept.size()));
  for (std::size_t l = 0; l < kept.size(); ++l)
    for (Eigen::Index a : *kept[l]) U(a, static_cast<Eigen::Index>(l)) = u(a);
  // The levels with too few points share one size, untested: their part of u joins the fitted
  // directions. Left in u's own column (which X holds), they would be tested as a level.
  Eigen::MatrixXd Xc = X;
  const Eigen::VectorXd rest_of_u = u - U.rowwise().sum();
  if (rest_of_u.norm() > 0) {
    Xc.conservativeResize(Eigen::NoChange, X.cols() + 1);
    Xc.col(X.cols()) = rest_of_u;
  }
  const BlockScore b = score_block(r, Xc, U);
  if (b.dof == 0) return c;
  c.levels = static_cast<int>(kept.size());
  c.statistic = b.statistic;
  c.dof = b.dof;
  // The residual outside the fitted and the tested directions sets the scale: under a correct model
  // S and the rest are sigma^2 chi^2(dof) and sigma^2 chi^2(rest_dof), independent, so their ratio
  // is Fisher's F for any common sigma, the stated noise right, understated or overstated. Without
  // rest degrees of freedom there is nothing to scale by: no test.
  const Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(Xc);
  c.rest_dof = informative_rows - static_cast<int>(qr.rank()) - b.dof;
  if (c.rest_dof <= 0) return FormCheck{};
  const Eigen::MatrixXd P = projector_out(Xc);
  const double rest = (P * r).squaredNorm() - b.statistic;
  c.scale = rest / c.rest_dof;
  c.p = split_p(c.statistic, rest, c.dof, c.rest_dof, r.squaredNorm());
  c.trend_noncentrality = trend_noncentrality(P, U, trend_of(kept_labels));
  if (law_size) set_law(c, X, u, level, P, U, kept_labels, law_size);
  return c;
}

double speed_law_size(const std::string& degrees, double exponent) {
  char* end = nullptr;
  const double theta = std::strtod(degrees.c_str(), &end);
  if (degrees.empty() || *end != '\0' || !(theta > 0 && theta <= 90)) return std::numeric_limits<double>::quiet_NaN();
  return std::pow(std::sin(theta * std::numbers::pi / 180), (exponent - 1) / 2);
}

double split_p(double statistic, double rest, int dof, int rest_dof, double residual_norm2) {
  if (rest > 0) return fisher_f_upper(statistic / dof / (rest / rest_dof), dof, rest_dof);
  // No rest at all (to rounding): the residual lies in the tested directions, an infinite F, unless
  // the statistic is itself rounding (a residual of nothing).
  return statistic > kRoundingShare * residual_norm2 && statistic > 0 ? 0.0 : 1.0;
}

double detectable_spread(const FormCheck& c, double departure, double alpha, double power) {
  if (std::isnan(c.trend_noncentrality)) return c.trend_noncentrality;  // no order to trend along
  const double per_unit = c.trend_noncentrality * departure * departure;  // lambda at spread 1
  if (!(per_unit > 0)) return std::numeric_limits<double>::infinity();
  return std::sqrt(min_detectable_noncentrality_f(c.dof, c.rest_dof, alpha, power) / per_unit);
}

std::vector<FormCheck> form_checks(const DataFile& data, const Surface& surface, const ModelState& after,
                                   const FormCheckDef& def) {
  std::vector<FormCheck> checks;
  if (surface.effects.empty()) return checks;
  // Every direction the fit used is projected out, a parameter left at an end of its range too.
  const SurfaceSlopes slopes = surface_slopes(data, surface, after.params, AtRangeEnd::one_sided);
  const FittedRows f = fitted_rows(data, surface, after, slopes);
  const auto parts = partitions(data, f.points);
  std::vector<double> departure;  // of each check's effect, key units
  for (const EffectTerm& e : surface.effects) {
    const auto at = std::find(slopes.keys.begin(), slopes.keys.end(), e.key);
    if (at == slopes.keys.end()) continue;  // no slope (a range of zero width)
    const Eigen::VectorXd u = f.X.col(at - slopes.keys.begin());
    for (const Partition& part : parts) {
      const LawSize law = law_along(part, find_effect(e.effect), data, def.other_law_exponent);
      FormCheck c = check_split(f.r, f.X, u, part.level, f.informative, def, law);
      if (c.dof == 0) continue;
      c.effect = e.effect;
      c.column = part.column;
      checks.push_back(c);
      departure.push_back(after.params.get(e.key, e.neutral) - e.neutral);
    }
  }
  const double m = static_cast<double>(checks.size());
  for (std::size_t i = 0; i < checks.size(); ++i) {
    FormCheck& c = checks[i];
    c.p_adjusted = std::min(1.0, c.p * m);
    c.spread_level = def.alpha / m;
    c.detectable_spread = detectable_spread(c, departure[i], c.spread_level, def.power);
    if (std::isfinite(c.law_noncentrality))
      c.law_power = f_test_power(c.law_noncentrality * departure[i] * departure[i], c.dof, c.rest_dof, c.spread_level);
  }
  return checks;
}

bool form_differs(const std::vector<FormCheck>& checks, double alpha) {
  return std::any_of(checks.begin(), checks.end(), [&](const FormCheck& c) { return c.p_adjusted < alpha; });
}

double law_power(const std::vector<FormCheck>& checks, const std::string& effect) {
  double best = std::numeric_limits<double>::quiet_NaN();
  for (const FormCheck& c : checks)
    if (c.effect == effect && std::isfinite(c.law_power) && !(c.law_power <= best)) best = c.law_power;
  return best;
}

double lowest_law_power(const std::vector<FormCheck>& checks, const std::vector<std::string>& added) {
  double lowest = std::numeric_limits<double>::quiet_NaN();
  for (const std::string& effect : added) {
    const EffectDef* e = find_effect(effect);
    if (e == nullptr || !e->speed_law) continue;
    double power = law_power(checks, effect);
    if (std::isnan(power)) power = 0;
    if (!(power >= lowest)) lowest = power;
  }
  return lowest;
}

bool laws_established(const std::vector<FormCheck>& checks, const std::vector<std::string>& added, double power,
                      double alpha) {
  for (const std::string& effect : added) {
    const EffectDef* e = find_effect(effect);
    if (e == nullptr || !e->speed_law) continue;
    const bool powered = law_power(checks, effect) >= power;  // NaN (no check asked): false
    const bool flagged = std::any_of(checks.begin(), checks.end(), [&](const FormCheck& c) {
      return c.effect == effect && std::isfinite(c.law_power) && c.p_adjusted < alpha;
    });
    if (!powered || flagged) return false;
  }
  return true;
}

}  // namespace gapflow

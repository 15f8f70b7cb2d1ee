#include "calibrate/detectability.hpp"

#include "calibrate/effect_catalogue.hpp"
#include "common/statistics.hpp"

#include <boost/math/distributions/fisher_f.hpp>
#include <boost/math/distributions/non_central_chi_squared.hpp>
#include <boost/math/distributions/non_central_f.hpp>
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace gapflow {

namespace {
constexpr double kInfinity = std::numeric_limits<double>::infinity();
}

double chi_square_test_power(double lambda, double dof, double alpha) {
  if (!(dof > 0) || !(alpha > 0 && alpha < 1) || std::isnan(lambda)) return std::numeric_limits<double>::quiet_NaN();
  const double critical = chi_square_quantile(1 - alpha, dof);
  if (lambda <= 0) return alpha;
  const boost::math::non_central_chi_squared dist(dof, lambda);
  return boost::math::cdf(boost::math::complement(dist, critical));
}

namespace {

// The smallest lambda at which power_at(lambda), rising with lambda, reaches `power` (bisection to
// a relative 1e-9); infinite where no lambda up to 1e9 does.
template <class PowerAt>
double smallest_noncentrality_with(PowerAt power_at, double power) {
  double lo = 0, hi = 1;
  while (power_at(hi) < power && hi < 1e9) hi *= 2;
  if (power_at(hi) < power) return kInfinity;
  for (int i = 0; i < 100 && hi - lo > 1e-9 * hi; ++i) {
    const double mid = 0.5 * (lo + hi);
    (power_at(mid) < power ? lo : hi) = mid;
  }
  return hi;
}

}  // namespace

double min_detectable_noncentrality(double dof, double alpha, double score_alpha, double power) {
  // No residual degrees of freedom: the chi^2 gate never rejects (chi_square_of gives p = 1), so
  // the loop attributes nothing at any size. Invalid levels or power: nothing to compute.
  if (!(dof > 0) || !(alpha > 0 && alpha < 1) || !(score_alpha > 0 && score_alpha < 1) || !(power > 0 && power < 1))
    return kInfinity;
  return smallest_noncentrality_with(
      [&](double lambda) {
        return std::min(chi_square_test_power(lambda, dof, alpha), chi_square_test_power(lambda, 1, score_alpha));
      },
      power);
}

namespace {

// The F test's power against lambda, its critical value given.
double f_power_beyond(double critical, double lambda, double d1, double d2, double alpha) {
  if (lambda <= 0) return alpha;
  return boost::math::cdf(boost::math::complement(boost::math::non_central_f(d1, d2, lambda), critical));
}

double f_critical(double d1, double d2, double alpha) {
  return boost::math::quantile(boost::math::complement(boost::math::fisher_f(d1, d2), alpha));
}

}  // namespace

double f_test_power(double lambda, double d1, double d2, double alpha) {
  if (!(d1 > 0) || !(d2 > 0) || !(alpha > 0 && alpha < 1) || std::isnan(lambda))
    return std::numeric_limits<double>::quiet_NaN();
  return f_power_beyond(f_critical(d1, d2, alpha), lambda, d1, d2, alpha);
}

double min_detectable_noncentrality_f(double d1, double d2, double alpha, double power) {
  if (!(d1 > 0) || !(d2 > 0) || !(alpha > 0 && alpha < 1) || !(power > 0 && power < 1)) return kInfinity;
  const double critical = f_critical(d1, d2, alpha);
  return smallest_noncentrality_with([&](double lambda) { return f_power_beyond(critical, lambda, d1, d2, alpha); },
                                     power);
}

namespace {

bool near(double a, double b, double scale) { return std::abs(a - b) <= 1e-9 * std::max(1.0, scale); }

Detectability entry_of(const Candidate& c, double lambda_star) {
  Detectability d;
  d.effect = c.effect;
  d.neutral = c.neutral;
  if (const EffectDef* e = find_effect(c.effect)) {
    d.unit = e->unit;
    d.lo = e->lo;
    d.hi = e->hi;
  }
  const bool other_larger = c.other_step != 0 && std::abs(c.other_step) > std::abs(c.step);
  d.largest_step = other_larger ? c.other_step : c.step;
  d.largest_step_p = other_larger ? c.other_visibility_p : c.visibility_p;
  const double scale = std::max(std::abs(d.lo), std::abs(d.hi));
  d.step_reached_range_end = near(d.neutral + d.largest_step, d.lo, scale) || near(d.neutral + d.largest_step, d.hi, scale);
  d.visible = c.visible;
  d.absorbed = c.visible && !(c.score.se > 0 && std::isfinite(c.score.se));
  if (d.visible && !d.absorbed) {
    d.min_departure = std::sqrt(lambda_star) * c.score.se;  // infinite when nothing can be detected
    d.within_range = d.neutral + d.min_departure <= d.hi || d.neutral - d.min_departure >= d.lo;
  }
  return d;
}

}  // namespace

std::vector<Detectability> detectability_at_baseline(const Round& baseline_round, int residual_dof,
                                                     const DetectabilityDef& def) {
  const auto visible = std::count_if(baseline_round.candidates.begin(), baseline_round.candidates.end(),
                                     [](const Candidate& c) { return c.visible; });
  const double score_alpha = def.alpha / static_cast<double>(std::max<std::ptrdiff_t>(1, visible));  // the loop's Bonferroni
  const double lambda_star = min_detectable_noncentrality(residual_dof, def.alpha, score_alpha, def.power);
  std::vector<Detectability> out;
  for (const Candidate& c : baseline_round.candidates) out.push_back(entry_of(c, lambda_star));
  return out;
}

std::string detectability_text(const Detectability& d) {
  const std::string unit = d.unit.empty() ? "" : " " + d.unit;
  if (d.absorbed) return "not detectable apart from the fitted parameters: they mimic its whole signature here";
  if (d.visible) {
    if (!std::isfinite(d.min_departure)) return "not detectable: the fit leaves no residual degrees of freedom";
    return d.within_range
               ? fmt::format("at best from a departure of {:.3g}{} (inside its plausible range [{:g}, {:g}])",
                             d.min_departure, unit, d.lo, d.hi)
               : fmt::format("not detectable in its plausible range [{:g}, {:g}]: needs a departure of {:.3g}{} at best",
                             d.lo, d.hi, d.min_departure, unit);
  }
  const double at = d.neutral + d.largest_step;
  const char* side = d.largest_step > 0 ? "upper" : "lower";
  return d.step_reached_range_end
             ? fmt::format("not seen even at its {} end ({:g}{}): the model moved within the noise there (p {:.2g}); "
                           "the other side untested",
                           side, at, unit, d.largest_step_p)
             : fmt::format("not seen at {:g}{} (the model moved within the noise, p {:.2g}); larger departures untested",
                           at, unit, d.largest_step_p);
}

}  // namespace gapflow

// Beverloo-type fit of the flow rate against the gap width.
//
//   J* = C (W/d - k)^beta,     J* = J sqrt(d/g)  (J in particles/s, d in m, g = 9.81 m/s^2)
//
// For a 2D slot Beverloo's law has beta = 3/2 (J ~ sqrt(g) (W - k d)^{3/2} in particles per
// unit time per unit density; see reference/physics-and-engines.md, "Flow through an aperture
// in 2D"). k (~1-2) is the "empty annulus" correction. The law holds only over a limited range
// of W/d (Mankoc et al. 2007): the fit reports the W/d range it used, and can be restricted.
//
// Method: weighted least squares, chi^2 = sum ((model_i - J*_i) / se_i)^2, se_i the standard
// error of the per-point mean. Start from a grid over k (log-linear regression for C, beta at
// each k), then Levenberg-Marquardt (Marquardt 1963, diagonal scaling) with Eigen, keeping
// W/d - k > 0 at every point. Parameter covariance = (J^T J)^-1 of the weighted residuals,
// multiplied by max(1, chi^2/dof) by default (so a poor model widens the intervals; the
// alternative assumes the se are exact and the model true). Intervals: value +- t_{dof} se.
// Optional: a bootstrap over runs (runs resampled within each point, refit, percentile interval).
#pragma once

#include "common/statistics.hpp"

#include <array>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

namespace gapflow {

struct BeverlooPoint {
  double w_over_d = 0;              // W/d
  double j_star = 0;                // mean of J sqrt(d/g) over runs (dimensionless)
  double se = kNaN;                 // standard error of that mean; <= 0 or NaN: unknown
  std::vector<double> run_values;   // per-run J* (optional: only for the bootstrap over runs)
};

// Mean and standard error (sd/sqrt(n)) of per-run values, keeping the values.
BeverlooPoint beverloo_point(double w_over_d, const std::vector<double>& run_values);

struct BeverlooOptions {
  bool fix_beta = false;            // true: fit C and k only, beta = beta_fixed
  double beta_fixed = 1.5;          // 2D Beverloo
  double x_min = -std::numeric_limits<double>::infinity();  // W/d range used (inclusive)
  double x_max = std::numeric_limits<double>::infinity();
  bool scale_by_chi2 = true;        // covariance *= max(1, chi^2/dof)
  double level = 0.95;
  int bootstrap_resamples = 0;      // > 0: bootstrap over runs (needs run_values, >= 2 per point)
  std::uint64_t seed = 0x62657665726c6f6full;
};

struct FitParameter {
  double value = kNaN;
  double se = kNaN;
  Interval ci;                      // value +- t_{(1+level)/2, dof} se
  Interval bootstrap_ci;            // percentile, when requested
  bool fixed = false;
};

struct BeverlooFit {
  bool ok = false;                  // converged with a valid covariance
  std::string message;              // why not, or notes (e.g. k at its bound)
  FitParameter C, k, beta;
  double chi2 = kNaN;
  int dof = 0;                      // points used - free parameters
  double chi2_per_dof = kNaN;
  std::string weighting;            // "standard errors", "standard errors (some filled by median)", "unweighted"
  std::size_t n_points = 0;         // used
  std::size_t n_outside_range = 0;  // excluded by x_min/x_max
  double x_lo = kNaN, x_hi = kNaN;  // W/d range of the points used: the law is claimed only there
  int iterations = 0;
  int bootstrap_failures = 0;
  std::array<std::array<double, 3>, 3> covariance{};  // order C, k, beta (zeros for a fixed beta)
  std::vector<double> x, y, se, fitted;               // the points used, and the model at them
  double predict(double w_over_d) const;
};

BeverlooFit fit_beverloo(const std::vector<BeverlooPoint>& points, const BeverlooOptions& opt = {});

}  // namespace gapflow

// Engine-independent statistics over runs.
//
// Everything here is deterministic: resampling uses gapflow::RandomStream with a
// seed given in the options (no rand(), no std::random_device), so the same input
// gives the same intervals bit for bit.
//
// Contents
//   * Student-t summary (summarize, student_t_975)              -- mean +- t s/sqrt(n)
//   * special functions (Boost.Math): regularized gamma/beta, normal, chi-square and
//     Student-t distribution and quantile functions
//   * describe(): mean + Student-t + bootstrap interval, median, and the paper's
//     "drop beyond 2 sigma" mean, side by side (never one silently chosen)
//   * censored exponential/geometric mean with the exact chi-square interval,
//     goodness-of-fit (KS distance + parametric bootstrap p-value, CV)
//   * Hill tail-exponent estimator
//   * two-sample comparison: ratio of means with a bootstrap interval + Welch t-test
#pragma once

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

namespace gapflow {

inline constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// ---------------------------------------------------------------------------
// Student-t summary (kept as it was: used by the CLI).
struct Summary {
  std::size_t n = 0;
  double mean = 0;
  double sd = 0;           // sample standard deviation (n - 1)
  double ci95_half = 0;    // half-width of the Student-t 95 % interval of the mean
  double lo() const { return mean - ci95_half; }
  double hi() const { return mean + ci95_half; }
  double se() const { return n > 0 ? sd / std::sqrt(static_cast<double>(n)) : 0.0; }
};

// Two-sided 95 % (one-sided 97.5 %) quantile of Student's t with `df` degrees of freedom:
// student_t_quantile(0.975, df); +inf for df = 0.
double student_t_975(std::size_t df);

Summary summarize(const std::vector<double>& values);

// ---------------------------------------------------------------------------
// Special functions and distributions, computed by Boost.Math (libboost-math-dev; its
// gamma_p, ibeta and the normal, chi_squared and students_t distributions), accurate to a
// few ulp over the whole range (large a or dof, p within 1e-300 of 0). Bad arguments give
// NaN, never an exception: each function checks its arguments as documented here, and the
// Boost error policy behind it turns a domain error into NaN and an overflow into +-inf.
//
// Regularized lower incomplete gamma P(a, x) = gamma(a, x)/Gamma(a), a > 0, x >= 0
// (0 at x = 0, 1 at x = +inf; NaN for a <= 0, x < 0 or NaN).
double regularized_gamma_p(double a, double x);
// Regularized incomplete beta I_x(a, b), a, b > 0, x in [0, 1] (NaN otherwise).
double regularized_beta(double x, double a, double b);

double normal_cdf(double z);                         // NaN for NaN
double normal_quantile(double p);                    // p in (0, 1); -inf at 0, +inf at 1, else NaN
double chi_square_cdf(double x, double dof);         // P(dof/2, x/2); 0 for x <= 0 (whatever dof)
// Inverse of chi_square_cdf, p in [0, 1] (0 at 0, +inf at 1); NaN for dof <= 0 or p outside.
double chi_square_quantile(double p, double dof);
// Upper tail of Fisher's F with (d1, d2) degrees of freedom, P(F > f) = I_{d2/(d2 + d1 f)}(d2/2, d1/2):
// 1 for f <= 0; NaN for d1 <= 0 or d2 <= 0.
double fisher_f_upper(double f, double d1, double d2);
double student_t_cdf(double t, double dof);           // any real dof > 0 (NaN otherwise)
double student_t_quantile(double p, double dof);      // inverse of student_t_cdf; p in (0, 1) open, else NaN

// ---------------------------------------------------------------------------
// Descriptive statistics of one sample (e.g. J of n runs).
struct Interval {
  double lo = kNaN;
  double hi = kNaN;
  bool valid() const { return lo == lo && hi == hi; }  // neither is NaN
  bool contains(double v) const { return valid() && v >= lo && v <= hi; }
  double width() const { return hi - lo; }
};

struct BootstrapOptions {
  int resamples = 2000;               // B
  std::uint64_t seed = 0x6a70666c6f77ull;
  double level = 0.95;                // two-sided
  // Expanded percentile interval (Hesterberg 2015, Am. Stat. 69:371, sec. 5): the plain
  // percentile interval of a mean is too narrow for small n (about 92.5 % coverage at n = 20
  // for normal data: it uses the plug-in sd, sqrt((n-1)/n) s, and z instead of t). The fix
  // takes the percentiles at alpha'/2, 1 - alpha'/2 with
  //   z_{alpha'/2} = sqrt(n/(n-1)) t_{alpha/2, n-1}
  // (alpha' = 0.032 at n = 20, -> alpha as n grows). Used by bootstrap_mean_interval only.
  bool expanded = true;
};

double median(std::vector<double> values);           // NaN when empty
// Type-7 (linear interpolation) quantile of a SORTED sample, q in [0, 1].
double sorted_quantile(const std::vector<double>& sorted, double q);

// Wilson score interval of a binomial proportion k/n (Wilson 1927) at the two-sided
// confidence 1 - alpha: stays inside [0, 1] and keeps its width at k = 0 or n, where
// the normal (Wald) interval collapses to a point. Invalid (NaN) for n = 0; throws
// std::invalid_argument for successes > n.
Interval wilson_interval(std::size_t successes, std::size_t n, double alpha = 0.05);

// Percentile bootstrap interval of the mean: B resamples of size n with
// replacement; [q_{a/2}, q_{1-a/2}] of the resampled means (Efron & Tibshirani 1993, ch. 13),
// with a expanded as described at BootstrapOptions::expanded (default). Invalid (NaN) for n < 2.
Interval bootstrap_mean_interval(const std::vector<double>& values, const BootstrapOptions& opt = {});

// The paper's rule (Murray & Alonso-Marroquin 2016, sec. IV): "data that were more
// than two standard deviations away from the mean were not included". One pass:
// drop |x - mean| > k sd (mean, sd of the full sample), recompute the summary.
// Note: with n values no point can be more than (n-1)/sqrt(n) sd from the mean,
// so for n <= 5 nothing is ever dropped at k = 2.
struct SigmaClipped {
  Summary kept;                 // Student-t summary of the values kept
  std::size_t dropped = 0;      // how many were dropped
  std::vector<double> dropped_values;
};
SigmaClipped drop_beyond_k_sigma(const std::vector<double>& values, double k = 2.0);

// All three views of one sample side by side.
struct SampleStatistics {
  Summary t;                    // mean, sd, Student-t 95 % interval
  Interval bootstrap;           // percentile bootstrap interval of the mean
  double median = kNaN;
  SigmaClipped clipped;         // mean after the paper's 2-sigma drop
};
SampleStatistics describe(const std::vector<double>& values, const BootstrapOptions& opt = {});

// ---------------------------------------------------------------------------
// Censored exponential mean (avalanche sizes, waiting times).
//
// Observations x_i, censored ones meaning "the true value is larger than x_i".
// Exponential likelihood: prod_unc (1/m) e^{-x/m} prod_cens e^{-x/m}
//   => MLE  m = (sum of ALL x, censored included) / (number uncensored).
// Geometric on {1, 2, ...} with censoring "S > c": the same estimator, m = 1/p.
// 95 % interval: 2 sum / m ~ chi^2(2 n_unc) (exact without censoring and for
// type-II censoring; approximate for random censoring, e.g. Lawless 2003, sec. 3.2):
//   m in [2 sum / chi2_{0.975}(2 n_unc), 2 sum / chi2_{0.025}(2 n_unc)].
struct CensoredMean {
  std::size_t n = 0;
  std::size_t n_uncensored = 0;
  std::size_t n_censored = 0;
  double sum = 0;                 // all values
  double mean = kNaN;             // MLE (NaN when n_uncensored = 0)
  Interval ci95;
  double naive_mean = kNaN;       // mean of the uncensored values only (biased low)
};
CensoredMean censored_exponential_mean(const std::vector<double>& values,
                                       const std::vector<bool>& censored, double level = 0.95);

// Goodness of fit of an exponential (continuous data) or a geometric (integers >= 1)
// law with its mean fitted from the same data.
// Statistic: Kolmogorov-Smirnov distance D between the empirical CDF and the fitted
// CDF. Because the mean is estimated from the data (Lilliefors' problem) and the
// geometric law is discrete, the usual Kolmogorov table does not apply; the p-value
// is a parametric bootstrap instead: draw B samples of the same size from the fitted
// law, refit the mean, recompute D*; p = (1 + #{D* >= D}) / (B + 1).
// "consistent" means p >= alpha (default 0.05): not rejected at the 5 % level.
// Also reported: CV = sd/mean (1 for exponential, sqrt(1 - 1/m) for geometric).
struct TailCheckOptions {
  int resamples = 1000;
  std::uint64_t seed = 0x6b73746573747321ull;
  double alpha = 0.05;
  std::size_t min_n = 5;          // fewer values: not tested (consistent = true, tested = false)
};
struct TailCheck {
  std::string law;                // "exponential" or "geometric"
  std::size_t n = 0;
  double mean = kNaN;             // fitted mean
  double ks_distance = kNaN;
  double p_value = kNaN;
  double cv = kNaN;
  double cv_expected = kNaN;      // of the fitted law
  double alpha = 0.05;
  int from = 1;                   // smallest size tested (geometric_upper_tail_check)
  bool tested = false;
  bool consistent = true;         // p >= alpha (or not tested)
};
TailCheck exponential_tail_check(const std::vector<double>& values, const TailCheckOptions& opt = {});
TailCheck geometric_tail_check(const std::vector<int>& sizes, const TailCheckOptions& opt = {});
// The upper tail alone: the sizes >= from, shifted to s - from + 1, against the geometric
// law. If P(S = s) is proportional to q^s for s >= from, the shifted sizes are geometric on
// {1, 2, ...} whatever the law below `from` (memorylessness). Avalanche sizes measured in
// silos deviate from the exponential at small sizes and the exponential law is claimed for
// the tail (Zuriguel et al. 2005, PRE 71, 051303): this is the test of that claim.
// The result's n counts the sizes >= from; `from` is recorded.
TailCheck geometric_upper_tail_check(const std::vector<int>& sizes, int from, const TailCheckOptions& opt = {});
// KS distances alone (fitted mean given), exposed for tests.
double ks_distance_exponential(std::vector<double> values, double mean);
double ks_distance_geometric(std::vector<int> sizes, double mean);

// ---------------------------------------------------------------------------
// Hill estimator of a power-law tail P(X > x) ~ x^-alpha (Hill 1975).
// With the order statistics x_(1) >= x_(2) >= ... and k = floor(top_fraction n):
//   xi = (1/k) sum_{i=1..k} ln(x_(i) / x_(k+1)),  alpha = 1/xi,  se(alpha) ~ alpha/sqrt(k).
// alpha < 2: infinite variance (means over runs converge slowly); alpha <= 1: infinite mean.
// Caveat: on an exponential tail with top_fraction = 0.2 it gives alpha ~ 2 as well, so
// it indicates, it does not prove, a power law. Needs k >= 2 and positive values.
struct HillEstimate {
  std::size_t n = 0;
  std::size_t k = 0;
  double threshold = kNaN;        // x_(k+1)
  double alpha = kNaN;
  double alpha_se = kNaN;
  bool valid() const { return k >= 2 && alpha == alpha; }
};
HillEstimate hill_estimator(std::vector<double> values, double top_fraction = 0.2);

// ---------------------------------------------------------------------------
// Two independent samples: is mean(a) above mean(b)?
struct WelchTest {
  double t = kNaN;
  double dof = kNaN;              // Welch-Satterthwaite
  double p_two_sided = kNaN;
};
// t = (mean_a - mean_b) / sqrt(s_a^2/n_a + s_b^2/n_b),
// dof = (s_a^2/n_a + s_b^2/n_b)^2 / ((s_a^2/n_a)^2/(n_a-1) + (s_b^2/n_b)^2/(n_b-1))  (Welch 1947).
WelchTest welch_t_test(const std::vector<double>& a, const std::vector<double>& b);

enum class Verdict { significantly_above, significantly_below, not_distinguishable, insufficient_data };
const char* to_string(Verdict v);

// ratio = mean(a)/mean(b) with a plain percentile bootstrap interval (a and b resampled
// independently; `expanded` is not applied: there is no standard two-sample form, so for
// small samples the interval is slightly too narrow -- the Welch p-value is the cross-check).
// The verdict needs the interval AND the Welch test: lo > 1 above, hi < 1 below, each only
// when Welch's p < 1 - level; else not distinguishable; insufficient data with fewer than
// 2 values on either side.
struct RatioComparison {
  std::size_t n_a = 0, n_b = 0;
  double mean_a = kNaN, mean_b = kNaN;
  double ratio = kNaN;
  Interval ratio_ci;
  WelchTest welch;
  Verdict verdict = Verdict::insufficient_data;
  // Paired comparisons (compare_ratio_paired, common/paired_ratio.hpp): a[i] and b[i] share their
  // random numbers; ratio_ci is then Fieller's interval and the paired t-test replaces Welch's.
  bool paired = false;
  double correlation = kNaN;      // Pearson correlation of the pairs
  WelchTest paired_t;             // paired t-test of a - b (dof = n - 1)
  double p_value() const { return paired ? paired_t.p_two_sided : welch.p_two_sided; }
};
RatioComparison compare_ratio_of_means(const std::vector<double>& a, const std::vector<double>& b,
                                       const BootstrapOptions& opt = {});

}  // namespace gapflow

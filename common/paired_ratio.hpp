// Ratio of means of PAIRED samples (common random numbers): a[i] and b[i] come from runs
// that share their random numbers (e.g. the same replicate at an obstruction position and at
// the no-obstruction baseline: same particle sizes and placements, common/random.hpp), so
// their fluctuations may be correlated and the ratio mean(a)/mean(b) is estimated better
// than from two independent samples.
//
// Interval: Fieller's (Fieller 1954, JRSS B 16:175) for paired means. For the true ratio R
// the differences d_i = a_i - R b_i have mean 0, so
//   T(R) = mean(d) / (sd(d)/sqrt(n)),  sd(d)^2 = s_aa - 2 R s_ab + R^2 s_bb,
// is Student-t with n - 1 dof when the pairs are bivariate normal: the set {R : T(R)^2 <=
// t^2} is an EXACT interval there (a quadratic in R), and asymptotically right otherwise.
// Chosen over a paired bootstrap because the percentile bootstrap of a ratio undercovers at
// the 10-20 replicates a study has (statistics.hpp, compare_ratio_of_means), and over the
// delta method because Fieller is its exact small-sample form (the delta method is Fieller's
// first-order expansion) and stays honest when mean(b) is poorly determined (the set is
// then unbounded and the interval is reported as invalid, not as a too-narrow one).
// T(1) is the paired t-statistic of a - b, so the interval excludes 1 exactly when the
// paired t-test rejects at the same level: the verdict needs no second test.
#pragma once

#include "common/statistics.hpp"

#include <vector>

namespace gapflow {

// a and b are pairs (same index = same random numbers; equal sizes, else std::invalid_argument).
// Fewer than 2 pairs: insufficient data. n_a = n_b = the number of pairs.
RatioComparison compare_ratio_paired(const std::vector<double>& a, const std::vector<double>& b,
                                     double level = 0.95);

// Variance of the ratio estimate from the pairs over that from the same values taken as
// independent samples (delta method): (c_a^2 + c_b^2 - 2 rho c_a c_b) / (c_a^2 + c_b^2), c = sd/mean.
// < 1 when the pairs are positively correlated (about 1 - rho for equal CVs): the number of
// replicates an unpaired comparison needs for the same interval, times this factor. NaN for < 2 pairs.
double paired_variance_factor(const std::vector<double>& a, const std::vector<double>& b);

}  // namespace gapflow

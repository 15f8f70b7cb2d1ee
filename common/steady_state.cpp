#include "common/steady_state.hpp"

#include "common/statistics.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <stdexcept>

namespace gapflow {

namespace {

constexpr int kMinCrossingsPerBatch = 5;  // below this, batch means are too coarse for a t interval

void check_def(const SteadyStateDef& d) {
  if (!(d.bin_s > 0) || d.mser_batch_bins < 1 || d.min_batches < 2 || d.max_batches < d.min_batches ||
      !(d.autocorrelation_alpha > 0 && d.autocorrelation_alpha < 1) || !(d.level > 0 && d.level < 1))
    throw std::invalid_argument("SteadyStateDef: need bin_s > 0, mser_batch_bins >= 1, 2 <= min_batches <= "
                                "max_batches, alpha and level in (0, 1)");
}

// Rates (count / length) of k equal batches of [t0, t1]; `sorted` holds the crossing times.
std::vector<double> batch_rates(const std::vector<double>& sorted, double t0, double t1, int k) {
  const double length = (t1 - t0) / k;
  std::vector<double> rates(static_cast<std::size_t>(k), 0.0);
  auto it = std::lower_bound(sorted.begin(), sorted.end(), t0);
  for (; it != sorted.end() && *it <= t1; ++it) {
    const int b = std::min(k - 1, static_cast<int>((*it - t0) / length));
    rates[static_cast<std::size_t>(b)] += 1.0;
  }
  for (double& r : rates) r /= length;
  return rates;
}

double clogged_time(const std::vector<Clog>& clogs, double t0, double t1) {
  double s = 0;
  for (const Clog& c : clogs) s += std::max(0.0, std::min(t1, c.t_start + c.duration) - std::max(t0, c.t_start));
  return s;
}

}  // namespace

std::vector<double> bin_counts(const std::vector<double>& times, double t_end_s, double bin_s) {
  const auto n = static_cast<std::size_t>(std::max(0.0, std::floor(t_end_s / bin_s)));
  std::vector<double> counts(n, 0.0);
  for (double t : times) {
    if (!(t >= 0)) continue;
    const auto i = static_cast<std::size_t>(t / bin_s);
    if (i < n) counts[i] += 1.0;
  }
  return counts;
}

MserTruncation mser_truncation(const std::vector<double>& series, int batch) {
  const std::size_t b = static_cast<std::size_t>(std::max(1, batch));
  const std::size_t m = series.size() / b;
  if (m < 2) return {};
  std::vector<double> z(m);
  for (std::size_t j = 0; j < m; ++j)
    z[j] = std::accumulate(series.begin() + static_cast<std::ptrdiff_t>(j * b),
                           series.begin() + static_cast<std::ptrdiff_t>((j + 1) * b), 0.0) / static_cast<double>(b);
  // Suffix sums of z and z^2: MSER(d) = (S2 - S1^2/n) / n^2 with n = m - d.
  std::vector<double> s1(m + 1, 0.0), s2(m + 1, 0.0);
  for (std::size_t j = m; j-- > 0;) {
    s1[j] = s1[j + 1] + z[j];
    s2[j] = s2[j + 1] + z[j] * z[j];
  }
  const std::size_t limit = m / 2;
  std::size_t best = 0;
  double best_value = INFINITY;
  for (std::size_t d = 0; d <= limit; ++d) {
    const double n = static_cast<double>(m - d);
    const double value = std::max(0.0, s2[d] - s1[d] * s1[d] / n) / (n * n);
    if (value < best_value) best_value = value, best = d;  // first minimum: the shortest truncation
  }
  return {best * b, best == limit};
}

double lag1_autocorrelation(const std::vector<double>& x) {
  if (x.size() < 3) return 0.0;
  const double mean = std::accumulate(x.begin(), x.end(), 0.0) / static_cast<double>(x.size());
  double num = 0, den = 0;
  for (std::size_t i = 0; i < x.size(); ++i) {
    den += (x[i] - mean) * (x[i] - mean);
    if (i + 1 < x.size()) num += (x[i] - mean) * (x[i + 1] - mean);
  }
  return den > 0 ? num / den : 0.0;
}

SteadyStateEstimate estimate_steady_state(const std::vector<double>& times, double t_end_s,
                                          const std::vector<Clog>& clogs, const SteadyStateDef& def) {
  check_def(def);
  SteadyStateEstimate e;
  const double mser_batch_s = def.bin_s * def.mser_batch_bins;
  if (!(std::isfinite(t_end_s) && t_end_s >= 2 * mser_batch_s)) {
    e.why_not = fmt::format("the run is shorter than two MSER batches ({:g} s)", 2 * mser_batch_s);
    return e;
  }
  std::vector<double> sorted;
  sorted.reserve(times.size());
  for (double t : times)
    if (t >= 0 && t <= t_end_s) sorted.push_back(t);
  std::sort(sorted.begin(), sorted.end());

  if (def.fixed_truncation_s >= 0) {
    e.truncation_s = std::min(def.fixed_truncation_s, t_end_s - mser_batch_s);
  } else {
    const MserTruncation cut = mser_truncation(bin_counts(sorted, t_end_s, def.bin_s), def.mser_batch_bins);
    e.truncation_s = static_cast<double>(cut.drop) * def.bin_s;
    e.transient_at_limit = cut.at_limit;
  }
  e.window_s = t_end_s - e.truncation_s;
  e.crossings = static_cast<int>(sorted.end() - std::lower_bound(sorted.begin(), sorted.end(), e.truncation_s));
  e.clogged_s = clogged_time(clogs, e.truncation_s, t_end_s);
  if (e.crossings < kMinCrossingsPerBatch * def.min_batches) {
    e.why_not = fmt::format("{} crossings after the transient: batch means need at least {}", e.crossings,
                            kMinCrossingsPerBatch * def.min_batches);
    return e;
  }

  // Longer batches while their means are significantly positively autocorrelated.
  const double z = normal_quantile(1 - def.autocorrelation_alpha);
  std::vector<double> rates;
  for (int k = def.max_batches;; k = std::max(def.min_batches, 2 * k / 3)) {
    rates = batch_rates(sorted, e.truncation_s, t_end_s, k);
    e.batches = k;
    e.lag1_autocorrelation = lag1_autocorrelation(rates);
    e.autocorrelated = e.lag1_autocorrelation > z / std::sqrt(static_cast<double>(k));
    if (!e.autocorrelated || k == def.min_batches) break;
  }
  e.batch_s = e.window_s / e.batches;
  e.j_per_s = e.crossings / e.window_s;  // = the mean of the batch rates
  const Summary s = summarize(rates);
  e.half_width_per_s = student_t_quantile(0.5 + def.level / 2, e.batches - 1) * s.sd / std::sqrt(double(e.batches));
  e.valid = true;
  return e;
}

std::string steady_state_line(const SteadyStateEstimate& e) {
  if (!e.valid) return "J (steady)    n/a   [" + e.why_not + "]";
  std::string line = fmt::format(
      "J (steady)    {:8.2f} /s +- {:.2f} ({:.1f} %, 95 %, batch means: {} x {:.1f} s, lag-1 r {:+.2f})   "
      "[re-injected pile; window {:.1f}-{:.1f} s after a transient found by MSER-5; clogs inside: {:.1f} s]",
      e.j_per_s, e.half_width_per_s, 100 * e.relative_half_width(), e.batches, e.batch_s, e.lag1_autocorrelation,
      e.truncation_s, e.truncation_s + e.window_s, e.clogged_s);
  if (e.autocorrelated) line += "\n              warning: batch means still autocorrelated at the fewest batches: interval too narrow, run longer";
  if (e.transient_at_limit) line += "\n              warning: the transient did not end within the first half of the run: run longer";
  return line;
}

std::optional<SteadyStateEstimate> steady_state_of(const RunRecord& r, std::optional<double> until_s,
                                                   const SteadyStateDef& def) {
  if (r.reinjected <= 0) return std::nullopt;
  const double t_end = until_s ? std::min(*until_s, r.sim_time_s) : r.sim_time_s;
  std::vector<double> times;
  times.reserve(r.crossings.size());
  for (const Crossing& c : r.crossings) times.push_back(c.t);
  return estimate_steady_state(times, t_end, r.clogs, def);
}

}  // namespace gapflow

#include "calibrate/effect_term.hpp"

#include "calibrate/node_correlation.hpp"

#include <algorithm>
#include <cmath>

// Boost 1.74's pchip.hpp (Debian 12) calls isnan unqualified; later Boost qualifies it.
using std::isnan;
#include <boost/math/interpolators/pchip.hpp>

namespace gapflow {

// The cubic through one point's shifts, and the same cubic with each measured size's shift moved up
// and down by `nudge` in turn: their differences at a size give the cubic's weights on the sizes, for
// its variance. Both sides, since it is not linear in them and not everywhere smooth: its slopes are
// harmonic means, and clamped to 0 where the secants turn, which is where an even response's end
// slope at neutral sits (a tilt's: there the two sides' weights differ, 3.6 x at 0.5 deg on a
// quadratic through 0, 2, 4, 6 deg, more toward neutral).
struct SmoothResponse {
  using Pchip = boost::math::interpolators::pchip<std::vector<double>>;
  Pchip at;
  std::vector<Pchip> up, down;  // [size]: the shift at that size moved up, down by nudge
  double nudge = 0;             // fit scale

  // The weight of size j at da: the one-sided one of larger magnitude.
  double weight(std::size_t j, double da, double value) const {
    const double above = (up[j](da) - value) / nudge, below = (value - down[j](da)) / nudge;
    return std::abs(above) >= std::abs(below) ? above : below;
  }
};

namespace {

// The slope of a PCHIP at an end (x[0], or x[n-1] with `last`): the three-point formula (the
// derivative there of the parabola through the three end sizes), kept shape-preserving (0 where it
// points against the end segment; at most 3 times the end segment's slope where the segments turn),
// as Fritsch and Carlson's and MATLAB's pchip do. Boost 1.74's default is the end segment's own
// slope, which on a response even in its effect (a tilt's J: slope 0 at neutral) reads a quadratic's
// 1 deg as 0.56, as biased toward neutral as a straight line.
double end_slope(const std::vector<double>& x, const std::vector<double>& y, bool last) {
  const std::size_t n = x.size();
  const std::size_t a = last ? n - 1 : 0, b = last ? n - 2 : 1, c = last ? n - 3 : 2;
  const double h0 = x[b] - x[a], h1 = x[c] - x[b];  // signed: negative from the last end
  const double d0 = (y[b] - y[a]) / h0, d1 = (y[c] - y[b]) / h1;
  const double d = ((2 * h0 + h1) * d0 - h0 * d1) / (h0 + h1);
  if (d * d0 <= 0) return 0.0;
  if (d0 * d1 < 0 && std::abs(d) > 3 * std::abs(d0)) return 3 * d0;
  return d;
}

SmoothResponse::Pchip pchip_through(const std::vector<double>& x, std::vector<double> y) {
  const double left = end_slope(x, y, false), right = end_slope(x, y, true);
  return SmoothResponse::Pchip(std::vector<double>(x), std::move(y), left, right);
}

SmoothResponse smooth_response(const std::vector<double>& x, std::vector<double> y) {
  double scale = 0;
  for (double v : y) scale = std::max(scale, std::abs(v));
  SmoothResponse r{pchip_through(x, y), {}, {}, 1e-7 * std::max(scale, 1e-9)};
  for (std::size_t j = 0; j < y.size(); ++j) {
    for (const double sign : {1.0, -1.0}) {
      std::vector<double> moved = y;
      moved[j] += sign * r.nudge;
      (sign > 0 ? r.up : r.down).push_back(pchip_through(x, std::move(moved)));
    }
  }
  return r;
}

// Where the sizes' correlation is not counted (a term whose sizes are not all paired alike, or too few
// points pooled; every term in blind passes up to 25): the largest variance of sum_j w_j e_j over the
// sizes' errors e_j (standard errors s_j) when their correlations lie in [0, 1] (the sizes' shifts
// share the neutral runs and their seeds, which correlates them positively; a negative correlation is
// not allowed for): it is linear in each
// correlation, so the largest is at 1 where the two weights agree in sign and 0 where
// they do not, (sum of w_j s_j over w_j > 0)^2 + (sum of |w_j| s_j over w_j < 0)^2. For a straight
// line between two sizes this is ((1-w) sa + w sb)^2 (exact next to neutral, where sa = 0), and
// beyond the end sizes (1-w)^2 va + w^2 vb. The independent case's variance, which dips to half at
// mid-segment, drew fits to the sizes or away from them (pass 6). Where the cubic's weights differ
// by side (SmoothResponse::weight), the larger of each: on the tilt's quadratic through 0, 2, 4 and
// 6 deg this holds the spread of its value at 0.5-5 deg for correlations 0 and 1; with full
// correlation the spread is 0.87 of it at 3 deg, 0.85 at 5, 0.47 at 1 and 0.23 at 0.5 (conservative
// near neutral; EffectTermResponse.TheCubicsVarianceCountsEverySizeItLeansOn prints them).
struct VarianceBound {
  double positive = 0, negative = 0;
  void add(double weight, double se) { (weight > 0 ? positive : negative) += std::abs(weight) * se; }
  double value() const { return positive * positive + negative * negative; }
};

// Point i's pairs at every size but neutral, [pair][size], the pairs complete at every such size only,
// each column standardized (node_correlation.hpp); empty with fewer than 3 such pairs or a size whose
// differences do not vary (a point the effect does not reach: its runs are identical).
Eigen::MatrixXd standardized_pairs(const EffectTerm& t, std::size_t i, const std::vector<std::size_t>& sizes) {
  const std::size_t n = t.pairs[sizes.front()][i].size();
  std::vector<std::size_t> complete;
  for (std::size_t r = 0; r < n; ++r)
    if (std::all_of(sizes.begin(), sizes.end(), [&](std::size_t j) { return std::isfinite(t.pairs[j][i][r]); }))
      complete.push_back(r);
  if (complete.size() < 3) return {};
  Eigen::MatrixXd z(static_cast<Eigen::Index>(complete.size()), static_cast<Eigen::Index>(sizes.size()));
  for (std::size_t r = 0; r < complete.size(); ++r)
    for (std::size_t k = 0; k < sizes.size(); ++k)
      z(static_cast<Eigen::Index>(r), static_cast<Eigen::Index>(k)) = t.pairs[sizes[k]][i][complete[r]];
  return standardize_columns(z) ? z : Eigen::MatrixXd{};
}

// The sizes but neutral, when every one has its pairs, the same number at each point; else none.
std::vector<std::size_t> sizes_paired_alike(const EffectTerm& t) {
  std::vector<std::size_t> sizes;
  for (std::size_t j = 0; j < t.offsets.size(); ++j) {
    if (t.offsets[j] == 0) continue;
    if (t.pairs[j].size() != t.shift[j].size()) return {};
    sizes.push_back(j);
  }
  for (std::size_t i = 0; !sizes.empty() && i < t.shift.front().size(); ++i)
    for (std::size_t j : sizes)
      if (t.pairs[j][i].size() != t.pairs[sizes.front()][i].size()) return {};
  return sizes;
}

// Point i's moments behind the partner share at size j, over the pairs whose partner and difference
// are both known: the partners' within-node covariance with the differences, as a sum over the
// within-node degrees of freedom (each node's partners centred over those pairs), and the
// differences' sum of squares over theirs. The pairs run node by node, the same number at each
// (EffectTerm::partners). Both 0 where the pairs do not split evenly over the nodes or leave fewer
// than two degrees of freedom.
struct ShareMoments {
  double covariance = 0, variance = 0;  // fit scale squared: Cov(b, d) and Var(d) estimates
};
ShareMoments share_moments(const EffectTerm& t, std::size_t i, std::size_t j) {
  const std::vector<double>& b = t.partners[i];
  const std::vector<double>& d = t.pairs[j][i];
  const std::size_t nodes = std::max<std::size_t>(t.paired_with.size(), 1);
  if (d.size() % nodes != 0) return {};
  const std::size_t per_node = d.size() / nodes;
  double cross = 0, n = 0, sum = 0, squares = 0;
  std::size_t used_nodes = 0;
  for (std::size_t k = 0; k < nodes; ++k) {
    double nk = 0, bk = 0;
    for (std::size_t r = k * per_node; r < (k + 1) * per_node; ++r)
      if (std::isfinite(b[r]) && std::isfinite(d[r])) bk += b[r], ++nk;
    if (nk == 0) continue;
    ++used_nodes;
    for (std::size_t r = k * per_node; r < (k + 1) * per_node; ++r) {
      if (!std::isfinite(b[r]) || !std::isfinite(d[r])) continue;
      cross += (b[r] - bk / nk) * d[r], sum += d[r], squares += d[r] * d[r];
    }
    n += nk;
  }
  if (n < static_cast<double>(used_nodes) + 2) return {};
  return {cross / (n - static_cast<double>(used_nodes)), (squares - sum * sum / n) / (n - 1)};
}

// Each group's partner share per size: the partners' covariance with the differences over the
// differences' variance, each summed over the group's points (a ratio of sums, so that a point the
// effect hardly moves, whose differences hardly vary, cannot swing it), where the partners are known
// and at least kMinPoints of the group's points have differences that vary at every size; else
// left empty (-1/2).
void add_partner_shares(const EffectTerm& t, const std::vector<std::size_t>& sizes, std::vector<SizeCorrelation>& out) {
  const std::size_t points = t.shift.front().size();
  if (t.partners.size() != points) return;
  for (std::size_t i = 0; i < points; ++i)
    if (t.partners[i].size() != t.pairs[sizes.front()][i].size()) return;
  for (std::size_t g = 0; g < out.size(); ++g) {
    std::vector<ShareMoments> sum(t.offsets.size());
    int pooled = 0;
    for (std::size_t i = 0; i < points; ++i) {
      if ((t.pooled_in.empty() ? 0 : t.pooled_in[i]) != g) continue;
      std::vector<ShareMoments> at(t.offsets.size());
      bool every = true;
      for (std::size_t j : sizes) every = every && (at[j] = share_moments(t, i, j)).variance > 0;
      if (!every) continue;
      for (std::size_t j : sizes) sum[j].covariance += at[j].covariance, sum[j].variance += at[j].variance;
      ++pooled;
    }
    if (pooled < SizeCorrelation::kMinPoints) continue;
    out[g].partner_share.assign(t.offsets.size(), -0.5);
    for (std::size_t j : sizes)  // held within [-1, 1]: below -1 (moved runs that keep much of a noisier partner) the
                                 // larger covariance is not counted, which errs toward a larger variance
      out[g].partner_share[j] = std::clamp(sum[j].covariance / sum[j].variance, -1.0, 1.0);
  }
}

// The sizes' correlation per group of points; none (empty) unless every size but neutral is paired
// alike. Each entry clipped to [0, 1] (the bound's range: the shifts share their partners' noise), so
// that a group's estimate never states more than the bound, nor less than independent sizes.
std::vector<SizeCorrelation> size_correlations(const EffectTerm& t) {
  const std::vector<std::size_t> sizes = sizes_paired_alike(t);
  if (sizes.empty()) return {};
  const std::size_t groups = t.pooled_in.empty() ? 1 : *std::max_element(t.pooled_in.begin(), t.pooled_in.end()) + 1;
  const auto m = static_cast<Eigen::Index>(sizes.size());
  std::vector<Eigen::MatrixXd> gram(groups, Eigen::MatrixXd::Zero(m, m));
  std::vector<SizeCorrelation> out(groups);
  for (std::size_t i = 0; i < t.shift.front().size(); ++i) {
    const Eigen::MatrixXd z = standardized_pairs(t, i, sizes);
    if (z.size() == 0) continue;
    const std::size_t g = t.pooled_in.empty() ? 0 : t.pooled_in[i];
    gram[g] += z.transpose() * z;
    ++out[g].points;
  }
  const auto all = static_cast<Eigen::Index>(t.offsets.size());
  for (std::size_t g = 0; g < groups; ++g) {
    if (out[g].points < SizeCorrelation::kMinPoints) continue;
    out[g].matrix = Eigen::MatrixXd::Identity(all, all);
    for (Eigen::Index a = 0; a < m; ++a)
      for (Eigen::Index b = 0; b < m; ++b) {
        const auto j = static_cast<Eigen::Index>(sizes[static_cast<std::size_t>(a)]);
        const auto k = static_cast<Eigen::Index>(sizes[static_cast<std::size_t>(b)]);
        out[g].matrix(j, k) = std::clamp(gram[g](a, b) / out[g].points, 0.0, 1.0);
      }
  }
  add_partner_shares(t, sizes, out);
  return out;
}

}  // namespace

EffectTerm EffectTerm::single_step(std::string effect, std::string key, double neutral, double lo, double hi,
                                   double step, std::vector<double> slope, std::vector<double> slope_se) {
  EffectTerm t;
  t.effect = std::move(effect), t.key = std::move(key), t.neutral = neutral, t.lo = lo, t.hi = hi;
  t.offsets = {0.0};
  t.shift = {std::vector<double>(slope.size(), 0.0)};
  t.shift_se = t.shift;
  t.slope = std::move(slope), t.slope_se = std::move(slope_se);
  std::vector<double> at, se;
  for (std::size_t i = 0; i < t.slope.size(); ++i) at.push_back(t.slope[i] * step), se.push_back(std::abs(t.slope_se[i] * step));
  t.add_size(step, at, se);
  return t;
}

void EffectTerm::add_size(double da, std::vector<double> shift_at, std::vector<double> se_at,
                          std::vector<std::vector<double>> pairs_at) {
  pairs.resize(offsets.size());  // a term made field by field has none
  const auto k = static_cast<std::size_t>(std::lower_bound(offsets.begin(), offsets.end(), da) - offsets.begin());
  if (k < offsets.size() && offsets[k] == da) {
    shift[k] = std::move(shift_at), shift_se[k] = std::move(se_at), pairs[k] = std::move(pairs_at);
  } else {
    const auto at = static_cast<std::ptrdiff_t>(k);
    offsets.insert(offsets.begin() + at, da);
    shift.insert(shift.begin() + at, std::move(shift_at));
    shift_se.insert(shift_se.begin() + at, std::move(se_at));
    pairs.insert(pairs.begin() + at, std::move(pairs_at));
  }
  size_correlation = size_correlations(*this);
  smooth.assign(shift.front().size(), nullptr);
  if (offsets.size() < 4) return;  // PCHIP needs four sizes
  for (std::size_t i = 0; i < smooth.size(); ++i) {
    std::vector<double> y;
    for (const std::vector<double>& s : shift) y.push_back(s[i]);
    if (!std::all_of(y.begin(), y.end(), [](double v) { return std::isfinite(v); })) continue;
    smooth[i] = std::make_shared<const SmoothResponse>(smooth_response(offsets, std::move(y)));
  }
}

double EffectTerm::neighbour_correlation(std::size_t group) const {
  if (group >= size_correlation.size() || size_correlation[group].matrix.size() == 0) return NAN;
  double sum = 0;
  int n = 0;
  for (std::size_t j = 0; j + 1 < offsets.size(); ++j) {
    if (offsets[j] == 0 || offsets[j + 1] == 0) continue;
    sum += size_correlation[group].matrix(static_cast<Eigen::Index>(j), static_cast<Eigen::Index>(j + 1)), ++n;
  }
  return n > 0 ? sum / n : NAN;
}

double EffectTerm::neighbour_correlation() const {
  double sum = 0;
  int points = 0;
  for (std::size_t g = 0; g < size_correlation.size(); ++g) {
    const double c = neighbour_correlation(g);
    if (std::isnan(c)) continue;
    sum += c * size_correlation[g].points, points += size_correlation[g].points;
  }
  return points > 0 ? sum / points : NAN;
}

std::vector<double> EffectTerm::weights(std::size_t i, double da, double& value) const {
  std::vector<double> w(offsets.size(), 0.0);
  const bool inside = da >= offsets.front() && da <= offsets.back();
  if (inside && i < smooth.size() && smooth[i]) {
    const SmoothResponse& r = *smooth[i];
    value = r.at(da);
    for (std::size_t j = 0; j < offsets.size(); ++j) w[j] = r.weight(j, da, value);
    return w;
  }
  // A straight line through the segment that holds da (the end segments extend beyond the sizes).
  std::size_t k = 0;
  while (k + 2 < offsets.size() && da > offsets[k + 1]) ++k;
  const double t = (da - offsets[k]) / (offsets[k + 1] - offsets[k]);
  w[k] = 1 - t, w[k + 1] = t;
  value = shift[k][i] + t * (shift[k + 1][i] - shift[k][i]);
  return w;
}

// The paired covariance: each size's shift at point i is the mean, over N replicate pairs at the
// paired nodes (R at each), of d = m - b: a moved run less the node's run on the same seed. A node's
// fit value is the mean of its R runs, so its covariance with the shift is R (1/R) (1/N) Cov(b, d) =
// c Var(d)/N = c shift_se^2, at every paired node alike, with c = Cov(b, d)/Var(d) the partner share.
// With m and b of equal variance s^2 and correlation rho (common random numbers keep the packing, not
// the trajectory: rho is neither 0 nor 1), Cov(b, d) = rho s^2 - s^2 = -Var(d)/2 whatever rho: c = -1/2,
// what every pass up to 25 used. An effect that changes the noise breaks it: moved runs with 1.5 times
// their partners' sd (rho 0) give c = -1/3.25, and -1/2 then stated less than half the prediction's
// variance (tests/test_surface_noise.cpp); so c is read off the partners where they are known
// (SizeCorrelation::partner_share). The interpolant is linear in the shifts.
double EffectTerm::response(std::size_t i, double da, double& variance, double* paired_covariance) const {
  if (paired_covariance) *paired_covariance = 0;
  if (offsets.size() < 2) return variance = 0, 0.0;
  double value = 0;
  const std::vector<double> w = weights(i, da, value);
  const std::size_t group = pooled_in.empty() || i >= pooled_in.size() ? 0 : pooled_in[i];
  if (group < size_correlation.size() && size_correlation[group].matrix.size() > 0) {
    Eigen::VectorXd ws(static_cast<Eigen::Index>(offsets.size()));
    for (std::size_t j = 0; j < offsets.size(); ++j) ws(static_cast<Eigen::Index>(j)) = w[j] * shift_se[j][i];
    // Clipped to [0, 1] the matrix may not be a Gram matrix any more: never below 0.
    variance = std::max(ws.dot(size_correlation[group].matrix * ws), 0.0);
  } else {
    VarianceBound bound;
    for (std::size_t j = 0; j < offsets.size(); ++j) bound.add(w[j], shift_se[j][i]);
    variance = bound.value();
  }
  if (paired_covariance && !paired_with.empty()) {
    const bool read = group < size_correlation.size() && !size_correlation[group].partner_share.empty();
    const std::vector<double>* share = read ? &size_correlation[group].partner_share : nullptr;
    for (std::size_t j = 0; j < offsets.size(); ++j)
      *paired_covariance += w[j] * (share ? (*share)[j] : -0.5) * shift_se[j][i] * shift_se[j][i];
  }
  return value;
}

}  // namespace gapflow

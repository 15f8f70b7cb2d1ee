#include "common/paired_ratio.hpp"

#include <cmath>
#include <numeric>
#include <stdexcept>

namespace gapflow {

namespace {

// Means, sample (co)variances (n - 1) and correlation of the pairs.
struct PairMoments {
  double n = 0, mean_a = kNaN, mean_b = kNaN, s_aa = kNaN, s_bb = kNaN, s_ab = kNaN;
  double correlation() const { return s_aa > 0 && s_bb > 0 ? s_ab / std::sqrt(s_aa * s_bb) : kNaN; }
};

PairMoments moments(const std::vector<double>& a, const std::vector<double>& b) {
  if (a.size() != b.size()) throw std::invalid_argument("paired samples of different sizes");
  PairMoments m;
  m.n = static_cast<double>(a.size());
  if (a.empty()) return m;
  m.mean_a = std::accumulate(a.begin(), a.end(), 0.0) / m.n;
  m.mean_b = std::accumulate(b.begin(), b.end(), 0.0) / m.n;
  if (a.size() < 2) return m;
  double aa = 0, bb = 0, ab = 0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    const double da = a[i] - m.mean_a, db = b[i] - m.mean_b;
    aa += da * da, bb += db * db, ab += da * db;
  }
  m.s_aa = aa / (m.n - 1), m.s_bb = bb / (m.n - 1), m.s_ab = ab / (m.n - 1);
  return m;
}

// Fieller's set {R : (mean_a - R mean_b)^2 <= q (s_aa - 2 R s_ab + R^2 s_bb)}, q = t^2/n:
// A R^2 - 2 B R + C <= 0. Bounded only when A > 0 (mean_b is significantly non-zero); it then
// holds the point estimate, so the discriminant is >= 0.
Interval fieller(const PairMoments& m, double t) {
  const double q = t * t / m.n;
  const double A = m.mean_b * m.mean_b - q * m.s_bb;
  const double B = m.mean_a * m.mean_b - q * m.s_ab;
  const double C = m.mean_a * m.mean_a - q * m.s_aa;
  if (!(A > 0)) return {};
  const double root = std::sqrt(std::max(0.0, B * B - A * C));
  return {(B - root) / A, (B + root) / A};
}

}  // namespace

RatioComparison compare_ratio_paired(const std::vector<double>& a, const std::vector<double>& b, double level) {
  const PairMoments m = moments(a, b);
  RatioComparison r;
  r.paired = true;
  r.n_a = r.n_b = a.size();
  r.mean_a = m.mean_a, r.mean_b = m.mean_b;
  if (m.mean_b != 0) r.ratio = m.mean_a / m.mean_b;
  if (a.size() < 2) return r;
  r.correlation = m.correlation();
  const double dof = m.n - 1;
  const double var_diff = m.s_aa + m.s_bb - 2 * m.s_ab;  // of a - b
  if (var_diff > 0) {
    r.paired_t.t = (m.mean_a - m.mean_b) / std::sqrt(var_diff / m.n);
    r.paired_t.dof = dof;
    r.paired_t.p_two_sided = 2.0 * student_t_cdf(-std::abs(r.paired_t.t), dof);
  }
  r.ratio_ci = fieller(m, student_t_quantile(0.5 + 0.5 * level, dof));
  if (!(r.paired_t.p_two_sided == r.paired_t.p_two_sided)) {  // a - b constant: no test
    r.verdict = Verdict::not_distinguishable;
    return r;
  }
  const bool significant = r.paired_t.p_two_sided < 1.0 - level;
  r.verdict = !significant                   ? Verdict::not_distinguishable
              : m.mean_a > m.mean_b          ? Verdict::significantly_above
                                             : Verdict::significantly_below;
  return r;
}

double paired_variance_factor(const std::vector<double>& a, const std::vector<double>& b) {
  const PairMoments m = moments(a, b);
  if (a.size() < 2 || m.mean_a == 0 || m.mean_b == 0) return kNaN;
  const double va = m.s_aa / (m.mean_a * m.mean_a), vb = m.s_bb / (m.mean_b * m.mean_b);
  const double cov = m.s_ab / (m.mean_a * m.mean_b);
  return va + vb > 0 ? (va + vb - 2 * cov) / (va + vb) : kNaN;
}

}  // namespace gapflow

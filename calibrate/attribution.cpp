#include "calibrate/attribution.hpp"

#include "common/statistics.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>

namespace gapflow {

Eigen::MatrixXd projector_out(const Eigen::MatrixXd& X) {
  const Eigen::Index n = X.rows();
  Eigen::MatrixXd P = Eigen::MatrixXd::Identity(n, n);
  if (X.cols() == 0) return P;
  // Orthonormal basis of X's column space (rank-revealing QR: collinear columns are dropped).
  const Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(X);
  const Eigen::Index rank = qr.rank();
  const Eigen::MatrixXd Q = Eigen::MatrixXd(qr.householderQ()).leftCols(rank);
  return P - Q * Q.transpose();
}

double abs_cosine(const Eigen::VectorXd& a, const Eigen::VectorXd& b) {
  const double na = a.norm(), nb = b.norm();
  if (na == 0 || nb == 0) return 0;
  return std::abs(a.dot(b)) / (na * nb);
}

Score score_signature(const Eigen::VectorXd& r, const Eigen::MatrixXd& X, const Eigen::VectorXd& u) {
  const Eigen::VectorXd pu = projector_out(X) * u;
  Score s;
  s.projected_norm = pu.norm();
  s.signature_norm = u.norm();
  if (s.projected_norm == 0) return s;
  const double dot = pu.dot(r), nn = pu.squaredNorm();
  s.statistic = dot * dot / nn;
  s.p = 1 - chi_square_cdf(s.statistic, 1);
  s.estimate = dot / nn;
  s.se = 1 / s.projected_norm;
  return s;
}

BlockScore score_block(const Eigen::VectorXd& r, const Eigen::MatrixXd& X, const Eigen::MatrixXd& U) {
  BlockScore b;
  if (U.cols() == 0) return b;
  const Eigen::MatrixXd PU = projector_out(X) * U;
  // Nothing left once X is projected out (U within X's span, to rounding): no test.
  if (PU.norm() <= 1e-9 * U.norm()) return b;
  // An orthonormal basis of P U's column space (rank-revealing, relative to its largest column):
  // S is the squared length of r's share in it.
  Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(PU);
  qr.setThreshold(1e-9);
  b.dof = static_cast<int>(qr.rank());
  if (b.dof == 0) return b;
  const Eigen::MatrixXd Q = Eigen::MatrixXd(qr.householderQ()).leftCols(b.dof);
  b.statistic = (Q.transpose() * r).squaredNorm();
  b.p = 1 - chi_square_cdf(b.statistic, b.dof);
  return b;
}

bool size_direction_possible(double estimate, double neutral, double lo, double hi, double step) {
  const double room = estimate > 0 ? hi - neutral : estimate < 0 ? neutral - lo : 1.0;
  return room > 0.25 * std::abs(step);
}

std::vector<std::vector<int>> indistinguishable_groups(const std::vector<Eigen::VectorXd>& signatures,
                                                       const Eigen::MatrixXd& X, double threshold) {
  const Eigen::MatrixXd P = projector_out(X);
  std::vector<Eigen::VectorXd> projected;
  for (const Eigen::VectorXd& u : signatures) projected.push_back(P * u);
  const int n = static_cast<int>(signatures.size());
  std::vector<int> parent(static_cast<std::size_t>(n));
  std::iota(parent.begin(), parent.end(), 0);
  auto root = [&](int i) {
    while (parent[static_cast<std::size_t>(i)] != i) i = parent[static_cast<std::size_t>(i)];
    return i;
  };
  for (int i = 0; i < n; ++i)
    for (int j = i + 1; j < n; ++j)
      if (abs_cosine(projected[static_cast<std::size_t>(i)], projected[static_cast<std::size_t>(j)]) > threshold)
        parent[static_cast<std::size_t>(root(j))] = root(i);
  std::vector<std::vector<int>> groups;
  std::vector<int> group_of_root(static_cast<std::size_t>(n), -1);
  for (int i = 0; i < n; ++i) {
    int& g = group_of_root[static_cast<std::size_t>(root(i))];
    if (g < 0) {
      g = static_cast<int>(groups.size());
      groups.emplace_back();
    }
    groups[static_cast<std::size_t>(g)].push_back(i);
  }
  return groups;
}

ChiSquare chi_square_of(const Eigen::VectorXd& whitened_residual, int fitted_parameters) {
  ChiSquare c;
  c.chi2 = whitened_residual.squaredNorm();
  c.dof = static_cast<int>(whitened_residual.size()) - fitted_parameters;
  c.p = c.dof > 0 ? 1 - chi_square_cdf(c.chi2, c.dof) : 1.0;
  return c;
}

ChiSquare held_out_chi_square(const Eigen::VectorXd& r, const Eigen::MatrixXd& G, const Eigen::MatrixXd& X) {
  const Eigen::Index n = r.size();
  ChiSquare c;
  c.dof = static_cast<int>(n);
  if (n == 0) return c;
  Eigen::MatrixXd C = Eigen::MatrixXd::Identity(n, n);
  if (X.cols() > 0 && G.cols() == X.cols()) {
    // (X^T X)^+ : a parameter the fitted points do not constrain adds nothing rather than infinity.
    const Eigen::MatrixXd sigma = (X.transpose() * X).completeOrthogonalDecomposition().pseudoInverse();
    C += G * sigma * G.transpose();
  }
  c.chi2 = r.dot(C.ldlt().solve(r));
  c.p = 1 - chi_square_cdf(c.chi2, c.dof);
  return c;
}

double bic(double minus_two_log_likelihood, int parameters, int points) {
  return minus_two_log_likelihood + parameters * std::log(static_cast<double>(points));
}

Visibility step_visibility(const std::vector<std::vector<double>>& paired_differences,
                           const std::vector<bool>& held_out) {
  Visibility v;
  for (std::size_t i = 0; i < paired_differences.size(); ++i) {
    const std::vector<double>& d = paired_differences[i];
    if (held_out[i] || d.size() < 2) continue;
    const Summary s = summarize(d);
    if (s.se() > 0) {
      v.chi2 += (s.mean / s.se()) * (s.mean / s.se());
    } else if (s.mean != 0) {
      v.chi2 += 1e6;  // a deterministic shift
    } else {
      continue;  // identical runs: the step does not act on this point
    }
    ++v.dof;
  }
  v.p = v.dof > 0 ? 1 - chi_square_cdf(v.chi2, v.dof) : 1.0;
  return v;
}

std::vector<int> rivals_of(const std::vector<double>& scores, double delta) {
  std::vector<int> out;
  if (scores.empty()) return out;
  const double best = *std::max_element(scores.begin(), scores.end());
  for (std::size_t i = 0; i < scores.size(); ++i)
    if (best - scores[i] < delta) out.push_back(static_cast<int>(i));
  return out;
}

}  // namespace gapflow

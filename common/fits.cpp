#include "common/fits.hpp"

#include "common/random.hpp"

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <optional>

namespace gapflow {

BeverlooPoint beverloo_point(double w_over_d, const std::vector<double>& run_values) {
  const Summary s = summarize(run_values);
  return {w_over_d, s.mean, s.n >= 2 ? s.se() : kNaN, run_values};
}

double BeverlooFit::predict(double xv) const {
  const double base = xv - k.value;
  return base > 0 ? C.value * std::pow(base, beta.value) : kNaN;
}

namespace {

using Eigen::MatrixXd;
using Eigen::VectorXd;

struct Data {
  VectorXd x, y, s;  // W/d, J*, sigma
};

// Parameters are always (C, k, beta); `free` lists those that are fitted.
struct Problem {
  Data data;
  std::vector<int> free;
};

// Weighted residuals r_i = (C (x_i - k)^beta - y_i) / s_i; none when some x_i - k <= 0.
std::optional<VectorXd> residuals(const Data& d, const Eigen::Vector3d& p) {
  VectorXd r(d.x.size());
  for (Eigen::Index i = 0; i < d.x.size(); ++i) {
    const double base = d.x[i] - p[1];
    if (!(base > 0)) return std::nullopt;
    r[i] = (p[0] * std::pow(base, p[2]) - d.y[i]) / d.s[i];
  }
  return r;
}

// d r_i / d(C, k, beta) = (b^beta, -C beta b^(beta-1), C b^beta ln b) / s_i, b = x_i - k.
MatrixXd jacobian(const Problem& pr, const Eigen::Vector3d& p) {
  const Data& d = pr.data;
  MatrixXd j(d.x.size(), static_cast<Eigen::Index>(pr.free.size()));
  for (Eigen::Index i = 0; i < d.x.size(); ++i) {
    const double b = d.x[i] - p[1], pw = std::pow(b, p[2]);
    const double full[3] = {pw, -p[0] * p[2] * pw / b, p[0] * pw * std::log(b)};
    for (std::size_t c = 0; c < pr.free.size(); ++c)
      j(i, static_cast<Eigen::Index>(c)) = full[pr.free[c]] / d.s[i];
  }
  return j;
}

double cost(const Data& d, const Eigen::Vector3d& p) {
  const auto r = residuals(d, p);
  return r ? r->squaredNorm() : INFINITY;
}

// Starting point: for k on a grid below min(x), ln y = ln C + beta ln(x - k) is linear;
// solve it by weighted least squares (weight (y/s)^2, since sd(ln y) ~ s/y), keep the k
// whose parameters give the smallest chi^2 of the real model.
Eigen::Vector3d initial_guess(const Problem& pr, double beta_fixed) {
  const Data& d = pr.data;
  const bool fit_beta = pr.free.size() == 3;
  const double xmin = d.x.minCoeff(), span = std::max(d.x.maxCoeff() - xmin, 1.0);
  Eigen::Vector3d best(1, 0, beta_fixed);
  double best_cost = INFINITY;
  for (int g = 0; g <= 400; ++g) {
    const double kk = xmin - 1e-3 * span - (g / 400.0) * 3.0 * span;  // k in [xmin - 3 span, xmin)
    Eigen::Matrix2d a = Eigen::Matrix2d::Zero();
    Eigen::Vector2d rhs = Eigen::Vector2d::Zero();
    for (Eigen::Index i = 0; i < d.x.size(); ++i) {
      const double w = std::pow(d.y[i] / d.s[i], 2), lx = std::log(d.x[i] - kk), ly = std::log(d.y[i]);
      const Eigen::Vector2d row(1.0, fit_beta ? lx : 0.0);
      a += w * row * row.transpose();
      rhs += w * row * (fit_beta ? ly : ly - beta_fixed * lx);
    }
    if (!fit_beta) a(1, 1) = 1.0;  // beta not fitted: decouple it
    const Eigen::Vector2d sol = a.ldlt().solve(rhs);
    const Eigen::Vector3d p(std::exp(sol[0]), kk, fit_beta ? sol[1] : beta_fixed);
    const double c = cost(d, p);
    if (c < best_cost) best_cost = c, best = p;
  }
  return best;
}

struct LmResult {
  Eigen::Vector3d p;
  double cost = INFINITY;
  int iterations = 0;
  bool converged = false;
};

// Levenberg-Marquardt: solve (J^T J + lambda diag(J^T J)) delta = -J^T r; accept a step that
// lowers chi^2 (and keeps every x - k > 0) and relax lambda, else raise lambda and retry.
LmResult levenberg_marquardt(const Problem& pr, Eigen::Vector3d p) {
  LmResult out{p, cost(pr.data, p)};
  double lambda = 1e-3;
  for (int it = 0; it < 1000; ++it) {
    out.iterations = it + 1;
    const MatrixXd j = jacobian(pr, out.p);
    const VectorXd r = *residuals(pr.data, out.p);
    const MatrixXd a = j.transpose() * j;
    const VectorXd g = j.transpose() * r;
    MatrixXd damped = a;
    damped.diagonal() += lambda * a.diagonal().cwiseMax(1e-12);
    const VectorXd step = damped.ldlt().solve(-g);
    Eigen::Vector3d trial = out.p;
    for (std::size_t c = 0; c < pr.free.size(); ++c) trial[pr.free[c]] += step[static_cast<Eigen::Index>(c)];
    const double trial_cost = cost(pr.data, trial);
    if (trial_cost < out.cost) {
      const double gain = (out.cost - trial_cost) / std::max(out.cost, 1e-300);
      out.p = trial;
      out.cost = trial_cost;
      lambda = std::max(lambda / 10.0, 1e-12);
      if (gain < 1e-13) return out.converged = true, out;
    } else {
      lambda *= 10.0;
      // No step lowers chi^2 any more: at the minimum to machine precision.
      if (lambda > 1e12) return out.converged = true, out;
    }
  }
  return out;
}

struct Selected {
  Data data;
  std::vector<std::size_t> index;  // into the input points
  std::string weighting;
};

Selected select_points(const std::vector<BeverlooPoint>& pts, const BeverlooOptions& opt, BeverlooFit& fit) {
  std::vector<std::size_t> idx;
  for (std::size_t i = 0; i < pts.size(); ++i) {
    const auto& p = pts[i];
    if (p.w_over_d < opt.x_min || p.w_over_d > opt.x_max) {
      ++fit.n_outside_range;
      continue;
    }
    if (std::isfinite(p.w_over_d) && p.j_star > 0 && std::isfinite(p.j_star)) idx.push_back(i);
  }
  Selected s;
  s.index = idx;
  const auto n = static_cast<Eigen::Index>(idx.size());
  s.data.x.resize(n);
  s.data.y.resize(n);
  s.data.s.resize(n);
  std::vector<double> good_se;
  for (std::size_t i : idx)
    if (pts[i].se > 0 && std::isfinite(pts[i].se)) good_se.push_back(pts[i].se);
  // Points without a usable standard error get the median of the others (a point of one
  // run has none); with none at all the fit is unweighted and the covariance is always
  // rescaled by chi^2/dof, since the scale of the scatter is then unknown.
  const double fill = good_se.empty() ? 1.0 : median(good_se);
  s.weighting = good_se.empty()                  ? "unweighted"
                : good_se.size() == idx.size() ? "standard errors"
                                               : "standard errors (some filled by median)";
  for (Eigen::Index r = 0; r < n; ++r) {
    const BeverlooPoint& p = pts[idx[static_cast<std::size_t>(r)]];
    s.data.x[r] = p.w_over_d;
    s.data.y[r] = p.j_star;
    s.data.s[r] = (p.se > 0 && std::isfinite(p.se)) ? p.se : fill;
  }
  return s;
}

void fill_parameter(FitParameter& fp, double value, double variance, double t, bool fixed) {
  fp.value = value;
  fp.fixed = fixed;
  if (fixed || !(variance >= 0)) return;
  fp.se = std::sqrt(variance);
  if (std::isfinite(t)) fp.ci = {value - t * fp.se, value + t * fp.se};
}

// Covariance of the free parameters, expanded to 3x3; intervals from Student t.
void attach_uncertainties(const Problem& pr, const LmResult& lm, const BeverlooOptions& opt, bool unweighted,
                          BeverlooFit& fit) {
  const MatrixXd j = jacobian(pr, lm.p);
  const MatrixXd a = j.transpose() * j;
  Eigen::FullPivLU<MatrixXd> lu(a);
  const bool invertible = lu.isInvertible();
  MatrixXd cov = invertible ? MatrixXd(lu.inverse()) : MatrixXd::Zero(a.rows(), a.cols());
  if (fit.dof > 0 && (unweighted || opt.scale_by_chi2)) {
    const double f = unweighted ? fit.chi2_per_dof : std::max(1.0, fit.chi2_per_dof);
    cov *= f;
  }
  for (std::size_t r = 0; r < pr.free.size(); ++r)
    for (std::size_t c = 0; c < pr.free.size(); ++c)
      fit.covariance[pr.free[r]][pr.free[c]] = cov(static_cast<Eigen::Index>(r), static_cast<Eigen::Index>(c));
  const double t = fit.dof > 0 ? student_t_quantile(0.5 + 0.5 * opt.level, fit.dof) : kNaN;
  const bool have = invertible && fit.dof > 0;
  auto var = [&](int i) { return have ? fit.covariance[i][i] : kNaN; };
  fill_parameter(fit.C, lm.p[0], var(0), t, false);
  fill_parameter(fit.k, lm.p[1], var(1), t, false);
  fill_parameter(fit.beta, lm.p[2], var(2), t, opt.fix_beta);
  if (!invertible) fit.message += "singular normal matrix (parameters not identifiable); ";
  if (fit.dof <= 0) fit.message += "no degrees of freedom left: no intervals; ";
}

// Bootstrap over runs: resample the runs of each point (with replacement), refit from the
// full-data solution with the original weights; percentile intervals of C, k, beta.
void bootstrap_over_runs(const std::vector<BeverlooPoint>& pts, const Selected& sel, const Problem& pr,
                         const LmResult& lm, const BeverlooOptions& opt, BeverlooFit& fit) {
  for (std::size_t i : sel.index)
    if (pts[i].run_values.size() < 2) {
      fit.message += "bootstrap skipped: a point has fewer than 2 run values; ";
      return;
    }
  RandomStream rs(opt.seed);
  std::array<std::vector<double>, 3> samples;
  Problem boot = pr;
  for (int b = 0; b < opt.bootstrap_resamples; ++b) {
    for (std::size_t r = 0; r < sel.index.size(); ++r) {
      const auto& v = pts[sel.index[r]].run_values;
      double sum = 0;
      for (std::size_t m = 0; m < v.size(); ++m)
        sum += v[std::min(v.size() - 1, static_cast<std::size_t>(rs.uniform() * static_cast<double>(v.size())))];
      boot.data.y[static_cast<Eigen::Index>(r)] = sum / static_cast<double>(v.size());
    }
    const bool positive = (boot.data.y.array() > 0).all();
    const LmResult br = positive ? levenberg_marquardt(boot, lm.p) : LmResult{};
    if (!br.converged) {
      ++fit.bootstrap_failures;
      continue;
    }
    for (int p = 0; p < 3; ++p) samples[static_cast<std::size_t>(p)].push_back(br.p[p]);
  }
  FitParameter* params[3] = {&fit.C, &fit.k, &fit.beta};
  const double a = 0.5 * (1.0 - opt.level);
  for (int p = 0; p < 3; ++p) {
    auto& s = samples[static_cast<std::size_t>(p)];
    if (s.size() < 2 || params[p]->fixed) continue;
    std::sort(s.begin(), s.end());
    params[p]->bootstrap_ci = {sorted_quantile(s, a), sorted_quantile(s, 1.0 - a)};
  }
}

}  // namespace

BeverlooFit fit_beverloo(const std::vector<BeverlooPoint>& points, const BeverlooOptions& opt) {
  BeverlooFit fit;
  const Selected sel = select_points(points, opt, fit);
  fit.weighting = sel.weighting;
  fit.n_points = sel.index.size();
  Problem pr{sel.data, opt.fix_beta ? std::vector<int>{0, 1} : std::vector<int>{0, 1, 2}};
  if (fit.n_points < pr.free.size()) {
    fit.message = "too few points with J* > 0 in the W/d range";
    return fit;
  }
  fit.x_lo = sel.data.x.minCoeff();
  fit.x_hi = sel.data.x.maxCoeff();
  const LmResult lm = levenberg_marquardt(pr, initial_guess(pr, opt.beta_fixed));
  fit.iterations = lm.iterations;
  fit.chi2 = lm.cost;
  fit.dof = static_cast<int>(fit.n_points) - static_cast<int>(pr.free.size());
  fit.chi2_per_dof = fit.dof > 0 ? fit.chi2 / fit.dof : kNaN;
  attach_uncertainties(pr, lm, opt, sel.weighting == "unweighted", fit);
  // k pressed against min(W/d): the power law cannot bend further, the fit is at a boundary.
  if (fit.x_lo - lm.p[1] < 1e-6 * std::max(1.0, fit.x_lo)) fit.message += "k at its bound min(W/d); ";
  fit.x.assign(sel.data.x.data(), sel.data.x.data() + sel.data.x.size());
  fit.y.assign(sel.data.y.data(), sel.data.y.data() + sel.data.y.size());
  fit.se.assign(sel.data.s.data(), sel.data.s.data() + sel.data.s.size());
  for (double xv : fit.x) fit.fitted.push_back(fit.predict(xv));
  fit.ok = lm.converged && fit.C.se == fit.C.se;
  if (!lm.converged) fit.message += "Levenberg-Marquardt did not converge; ";
  if (opt.bootstrap_resamples > 0) bootstrap_over_runs(points, sel, pr, lm, opt, fit);
  return fit;
}

}  // namespace gapflow

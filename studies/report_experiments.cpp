// The experiment analyses of the report (numbers only; report_sections.cpp words them).
#include "studies/report.hpp"

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <set>

namespace gapflow {

// ---------------------------------------------------------------- flow_vs_gap

namespace {

// Per-run J* of one point (runs where J is undefined are left out, as in analyze_point).
std::vector<double> run_j_star(const ReportPoint& p, JKind j) {
  std::vector<double> v = j_values(p.stats, j);
  for (double& x : v) x *= p.stats.j_star_factor;
  return v;
}

bool has_distinct_w(const std::vector<const ReportPoint*>& pts) {
  std::set<double> w;
  for (const ReportPoint* p : pts)
    if (std::isfinite(p->stats.w_over_d)) w.insert(p->stats.w_over_d);
  return w.size() >= 2;
}

}  // namespace

FlowVsGapAnalysis analyze_flow_vs_gap(const ReportData& data, const ReportOptions& opt) {
  FlowVsGapAnalysis a;
  a.j = opt.j;
  for (const auto& [series, model] : series_models(data)) {
    const auto pts = points_of(data, series, model);
    if (series == opt.baseline || !has_distinct_w(pts)) continue;  // nothing to fit against W/d
    std::vector<BeverlooPoint> bp;
    for (const ReportPoint* p : pts) {
      const std::vector<double> v = run_j_star(*p, opt.j);
      if (!v.empty() && std::isfinite(p->stats.w_over_d)) bp.push_back(beverloo_point(p->stats.w_over_d, v));
    }
    BeverlooOptions free_opt;
    free_opt.x_min = opt.fit_w_min;
    free_opt.x_max = opt.fit_w_max;
    BeverlooOptions fixed_opt = free_opt;
    fixed_opt.fix_beta = true;
    a.fits.push_back({series, model, fit_beverloo(bp, free_opt), fit_beverloo(bp, fixed_opt)});
  }
  return a;
}

// ---------------------------------------------------------------- flow_vs_distance

namespace {

// Contiguous runs (in D order) of points whose verdict is `v`.
std::vector<DistanceRange> ranges_with(const std::vector<std::pair<double, Verdict>>& by_d, Verdict v) {
  std::vector<DistanceRange> out;
  bool open = false;
  for (const auto& [d, verdict] : by_d) {
    if (verdict != v) {
      open = false;
      continue;
    }
    if (!open) out.push_back({d, d, 0});
    open = true;
    out.back().to = d;
    out.back().n_points += 1;
  }
  return out;
}

DistanceResult distance_result(const ReportData& data, const std::string& series, const std::string& model,
                               const ReportOptions& opt) {
  DistanceResult r;
  r.series = series, r.model = model;
  auto pts = points_of(data, series, model);
  std::stable_sort(pts.begin(), pts.end(), [](const ReportPoint* a, const ReportPoint* b) {
    return a->stats.distance_over_d < b->stats.distance_over_d;
  });
  r.n_points = pts.size();
  const ReportPoint* peak = best_point(pts, opt.j);  // first of equals in D order, as before
  std::vector<std::pair<double, Verdict>> by_d;
  for (const ReportPoint* p : pts) {
    const ReportPoint* ref = baseline_for(data, *p);
    if (!ref) continue;
    const RatioComparison c = compare_to_baseline(p->stats, ref->stats, opt.j, {}, opt.pairing);
    by_d.emplace_back(p->stats.distance_over_d, c.verdict);
    if (c.verdict != Verdict::insufficient_data) ++r.n_compared;
  }
  r.above = ranges_with(by_d, Verdict::significantly_above);
  r.below = ranges_with(by_d, Verdict::significantly_below);
  if (!peak) return r;
  r.peak_label = peak->point_label;
  r.peak_d_over_d = peak->stats.distance_over_d;
  r.peak = mean_ci(j_stats(peak->stats, opt.j).t);
  if (const ReportPoint* ref = baseline_for(data, *peak)) {
    r.baseline = mean_ci(j_stats(ref->stats, opt.j).t);
    r.peak_gain = compare_to_baseline(peak->stats, ref->stats, opt.j, {}, opt.pairing);
  }
  return r;
}

}  // namespace

FlowVsDistanceAnalysis analyze_flow_vs_distance(const ReportData& data, const ReportOptions& opt) {
  FlowVsDistanceAnalysis a;
  a.j = opt.j;
  a.baseline = opt.baseline;
  for (const ReportPoint& p : data.points) a.baseline_found |= !opt.baseline.empty() && p.series == opt.baseline;
  for (const auto& [series, model] : series_models(data))
    if (series != opt.baseline) a.results.push_back(distance_result(data, series, model, opt));
  return a;
}

// ---------------------------------------------------------------- clogging

LineFit fit_line(const std::vector<double>& x, const std::vector<double>& y, const std::vector<double>& se) {
  LineFit f;
  f.n = x.size();
  const bool weighted =
      se.size() == x.size() && std::all_of(se.begin(), se.end(), [](double s) { return std::isfinite(s) && s > 0; });
  f.weighting = weighted ? "interval widths" : "unweighted";
  const auto n = static_cast<Eigen::Index>(f.n);
  // Design matrix [1 x], weights 1/se^2; normal matrix A = X^T W X, its inverse the covariance.
  Eigen::MatrixX2d design(n, 2);
  Eigen::VectorXd w(n), yv(n);
  for (Eigen::Index i = 0; i < n; ++i) {
    const auto k = static_cast<std::size_t>(i);
    design.row(i) << 1.0, x[k];
    w[i] = weighted ? 1.0 / (se[k] * se[k]) : 1.0;
    yv[i] = y[k];
  }
  const Eigen::Matrix2d a = design.transpose() * w.asDiagonal() * design;
  if (f.n < 2 || !(a.determinant() > 1e-12 * a(0, 0) * a(1, 1))) return f;  // fewer than two distinct x
  const Eigen::Matrix2d cov = a.inverse();
  const Eigen::Vector2d coef = cov * (design.transpose() * w.asDiagonal() * yv);
  f.intercept = coef[0];
  f.slope = coef[1];
  f.ok = true;
  if (f.n < 3) return f;  // exact through two points: no scatter left to estimate intervals
  const Eigen::VectorXd r = yv - design * coef;
  const double dof = static_cast<double>(f.n - 2);
  f.chi2_per_dof = r.dot(w.asDiagonal() * r) / dof;
  // Weighted: trust the se unless the scatter says they are too small (as fit_beverloo does).
  const double scale = weighted ? std::max(1.0, f.chi2_per_dof) : f.chi2_per_dof;
  const double t = student_t_quantile(0.975, dof);
  const double se_slope = std::sqrt(scale * cov(1, 1)), se_icpt = std::sqrt(scale * cov(0, 0));
  f.slope_ci = {f.slope - t * se_slope, f.slope + t * se_slope};
  f.intercept_ci = {f.intercept - t * se_icpt, f.intercept + t * se_icpt};
  return f;
}

CloggingAnalysis analyze_clogging(const ReportData& data) {
  CloggingAnalysis a;
  for (const auto& [series, model] : series_models(data)) {
    ClogSeries cs{series, model, {}, {}};
    for (const ReportPoint* p : points_of(data, series, model)) {
      ClogPoint c;
      c.point = p;
      c.w_over_d = p->stats.w_over_d;
      c.w2 = c.w_over_d * c.w_over_d;
      const CensoredMean& s = p->stats.avalanches.size;
      c.ln_s1 = std::log(s.mean + 1.0);  // NaN without uncensored avalanches
      c.ln_lo = std::log(s.ci95.lo + 1.0);
      c.ln_hi = std::log(s.ci95.hi + 1.0);
      cs.points.push_back(c);
    }
    std::stable_sort(cs.points.begin(), cs.points.end(),
                     [](const ClogPoint& l, const ClogPoint& r) { return l.w_over_d < r.w_over_d; });
    std::vector<double> x, y, se;
    for (const ClogPoint& c : cs.points) {
      if (!std::isfinite(c.ln_s1) || !std::isfinite(c.w2)) continue;
      x.push_back(c.w2);
      y.push_back(c.ln_s1);
      se.push_back((c.ln_hi - c.ln_lo) / (2 * 1.959963984540054));  // the chi-square interval, read as +-1.96 se
    }
    cs.fit = fit_line(x, y, se);
    a.series.push_back(std::move(cs));
  }
  return a;
}

// ---------------------------------------------------------------- models

double pearson_correlation(const std::vector<double>& a, const std::vector<double>& b) {
  const std::size_t n = std::min(a.size(), b.size());
  if (n < 2) return kNaN;
  const double ma = std::accumulate(a.begin(), a.begin() + static_cast<long>(n), 0.0) / static_cast<double>(n);
  const double mb = std::accumulate(b.begin(), b.begin() + static_cast<long>(n), 0.0) / static_cast<double>(n);
  double sab = 0, saa = 0, sbb = 0;
  for (std::size_t i = 0; i < n; ++i) {
    sab += (a[i] - ma) * (b[i] - mb);
    saa += (a[i] - ma) * (a[i] - ma);
    sbb += (b[i] - mb) * (b[i] - mb);
  }
  return saa > 0 && sbb > 0 ? sab / std::sqrt(saa * sbb) : kNaN;
}

namespace {

// Ranks 1..n, ties sharing their mean rank.
std::vector<double> ranks(const std::vector<double>& v) {
  std::vector<std::size_t> idx(v.size());
  std::iota(idx.begin(), idx.end(), 0);
  std::sort(idx.begin(), idx.end(), [&](std::size_t i, std::size_t j) { return v[i] < v[j]; });
  std::vector<double> r(v.size());
  for (std::size_t i = 0; i < idx.size();) {
    std::size_t j = i;
    while (j + 1 < idx.size() && v[idx[j + 1]] == v[idx[i]]) ++j;
    for (std::size_t k = i; k <= j; ++k) r[idx[k]] = 0.5 * static_cast<double>(i + j) + 1.0;
    i = j + 1;
  }
  return r;
}

}  // namespace

double spearman_correlation(const std::vector<double>& a, const std::vector<double>& b) {
  return pearson_correlation(ranks(a), ranks(b));
}

ModelsAnalysis analyze_models(const ReportData& data, const ReportOptions& opt) {
  ModelsAnalysis a;
  a.j = opt.j;
  std::vector<double> j2, j3, ratios;
  for (const ReportPoint& p2 : data.points) {
    if (p2.model != "2d") continue;
    for (const ReportPoint& p3 : data.points) {
      if (p3.model != "3d" || p3.series != p2.series || p3.point != p2.point) continue;
      ModelPair m;
      m.series = p2.series, m.point_label = p2.point_label, m.point = p2.point;
      m.j2d = mean_ci(j_stats(p2.stats, opt.j).t), m.j3d = mean_ci(j_stats(p3.stats, opt.j).t);
      m.j2d_star = j_star(p2.stats, opt.j), m.j3d_star = j_star(p3.stats, opt.j);
      m.ratio = compare_ratio_of_means(j_values(p2.stats, opt.j), j_values(p3.stats, opt.j));
      if (m.j2d.n > 0 && m.j3d.n > 0) {
        j2.push_back(m.j2d.mean), j3.push_back(m.j3d.mean);
        if (std::isfinite(m.ratio.ratio)) ratios.push_back(m.ratio.ratio);
      }
      a.pairs.push_back(std::move(m));
    }
  }
  a.n_both = j2.size();
  if (!ratios.empty())
    a.mean_ratio = std::accumulate(ratios.begin(), ratios.end(), 0.0) / static_cast<double>(ratios.size());
  a.pearson = pearson_correlation(j2, j3);
  a.spearman = spearman_correlation(j2, j3);
  return a;
}

}  // namespace gapflow

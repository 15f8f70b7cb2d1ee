// The experiment analyses as report sections: what was measured, the tables, the plots.
// Every number is formatted from the analysis structs (report_experiments.cpp).
#include "studies/report.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <numeric>

namespace gapflow {

namespace {

std::string model_name(const std::string& m) { return m == "2d" ? "2D" : m == "3d" ? "3D" : m; }
std::string label_or_single(const std::string& l) { return l.empty() ? "(single point)" : l; }

std::string param_text(const FitParameter& p) {
  if (p.fixed) return fmt_num(p.value) + " (fixed)";
  return fmt_num(p.value) + " " + fmt_interval(p.ci);
}

std::string ratio_text(const RatioComparison& r) {
  if (!std::isfinite(r.ratio)) return "n/a";
  return fmt_num(r.ratio, 4) + " " + fmt_interval(r.ratio_ci, 4);
}

std::string ranges_text(const std::vector<DistanceRange>& rs) {
  if (rs.empty()) return "none";
  std::string out;
  for (const DistanceRange& r : rs)
    out += (out.empty() ? "" : ", ") +
           (r.n_points == 1 ? fmt_num(r.from, 3) : fmt_num(r.from, 3) + "-" + fmt_num(r.to, 3));
  return out;
}

// A smooth curve of a Beverloo fit over the W/d range it used.
PlotLine beverloo_curve(const GapFit& g, const BeverlooFit& f, const char* style, const std::string& what) {
  PlotLine l;
  l.label = fmt::format("{} ({}) fit, {}", g.series, model_name(g.model), what);
  l.group = fmt::format("{} ({})", g.series,
                        model_name(g.model));  // the colour of its data
  l.model = g.model;
  l.style = style;
  if (!f.ok || !std::isfinite(f.x_lo) || !std::isfinite(f.x_hi)) return l;
  const int n = 60;
  for (int i = 0; i <= n; ++i) {
    const double x = f.x_lo + (f.x_hi - f.x_lo) * i / n;
    l.x.push_back(x), l.y.push_back(f.predict(x));
  }
  return l;
}

// "ok", the fit's own notes, or why there is no usable fit (drawn only when ok).
std::string fit_note(const BeverlooFit& f) {
  std::string m = f.message;
  while (!m.empty() && (m.back() == ' ' || m.back() == ';')) m.pop_back();
  if (f.ok) return m.empty() ? "ok" : m;
  return (std::isfinite(f.C.value) ? "not drawn: " : "failed: ") + m;
}

std::vector<std::string> fit_row(const GapFit& g, const BeverlooFit& f, const char* beta) {
  return {g.series,
          model_name(g.model),
          beta,
          param_text(f.C),
          param_text(f.k),
          param_text(f.beta),
          fmt_num(f.chi2_per_dof, 3),
          fmt::format("{}", f.n_points),
          fmt_ci(f.x_lo, f.x_hi, 3),
          fit_note(f)};
}

}  // namespace

// ---------------------------------------------------------------- flow_vs_gap

ExperimentSection flow_vs_gap_section(const ReportData& data, const ReportOptions& opt) {
  const FlowVsGapAnalysis a = analyze_flow_vs_gap(data, opt);
  ExperimentSection s;
  s.title = "Flow rate against the gap width (Beverloo fit)";
  s.paragraphs.push_back(
      fmt::format("J* = C (W/d - k)^beta, fitted by weighted least squares to "
                  "the per-point mean of {}* = {} sqrt(d/g) "
                  "(weights: standard errors of the means; 95 % intervals from "
                  "Student t, widened by sqrt(max(1, chi2/dof))), "
                  "for each series and model, with beta free and with the 2D "
                  "Beverloo value beta = 3/2. "
                  "The law is claimed only over the W/d range each fit used.",
                  to_string(a.j), to_string(a.j)));
  TextTable t;
  t.title = "Beverloo fits";
  t.header = {"series",        "model",    "beta",   "C [95% CI]", "k [95% CI]",
              "beta [95% CI]", "chi2/dof", "points", "W/d range",  "note"};
  const std::string overlay = j_star_figure_file("W/d");
  for (const GapFit& g : a.fits) {
    t.rows.push_back(fit_row(g, g.free_beta, "free"));
    t.rows.push_back(fit_row(g, g.fixed_beta, "3/2"));
    s.overlays[overlay].push_back(beverloo_curve(g, g.free_beta, "curve", "beta free"));
    s.overlays[overlay].push_back(beverloo_curve(g, g.fixed_beta, "curve_fixed", "beta = 3/2"));
  }
  if (a.fits.empty()) s.paragraphs.push_back("No series has two distinct W/d values: nothing to fit.");
  s.tables.push_back(std::move(t));
  return s;
}

// ---------------------------------------------------------------- flow_vs_distance

namespace {

std::string distance_sentence(const DistanceResult& r, JKind j) {
  std::string s = fmt::format("**{} ({})**: ", r.series, model_name(r.model));
  if (r.peak.n == 0) return s + fmt::format("no point has {} defined.", to_string(j));
  s += fmt::format("{} peaks at D/d = {} ({}) with {} = {} /s", to_string(j), fmt_num(r.peak_d_over_d, 3),
                   r.peak_label.empty() ? "single point" : r.peak_label, to_string(j), fmt_mean_ci(r.peak));
  if (!r.peak_gain) return s + "; no baseline to compare with.";
  s += fmt::format("; J_max/J_0 = {} ({}, {} p = {}).", ratio_text(*r.peak_gain), to_string(r.peak_gain->verdict),
                   r.peak_gain->paired ? "paired by replicate, paired t" : "Welch",
                   fmt_num(r.peak_gain->p_value(), 3));
  auto where = [](const std::vector<DistanceRange>& rs, const char* side) {
    return rs.empty() ? fmt::format("nowhere significantly {} J_0", side)
                      : fmt::format("significantly {} J_0 at D/d = {}", side, ranges_text(rs));
  };
  s += fmt::format(" {} is {}, and {} ({} of {} points compared).", to_string(j), where(r.above, "above"),
                   where(r.below, "below"), r.n_compared, r.n_points);
  return s;
}

PlotFigure ratio_figure(const ReportData& data, const ReportOptions& opt) {
  PlotFigure f{"ratio_vs_D_over_d.png",
               fmt::format("{} / {} of the baseline '{}'", to_string(opt.j), to_string(opt.j), opt.baseline),
               "D/d",
               "J/J_0 (95% CI: bootstrap, or Fieller where paired)",
               {},
               {{"J = J_0", "", 1.0, 1.0, 1.0}},
               false};
  for (const auto& [series, model] : series_models(data)) {
    if (series == opt.baseline) continue;
    PlotLine l;
    l.label = fmt::format("{} ({})", series, model_name(model));
    l.model = model;
    auto pts = points_of(data, series, model);
    std::stable_sort(pts.begin(), pts.end(), [](const ReportPoint* a, const ReportPoint* b) {
      return a->stats.distance_over_d < b->stats.distance_over_d;
    });
    for (const ReportPoint* p : pts) {
      const ReportPoint* ref = baseline_for(data, *p);
      if (!ref) continue;
      const RatioComparison c = compare_to_baseline(p->stats, ref->stats, opt.j, {}, opt.pairing);
      if (!std::isfinite(c.ratio)) continue;
      l.x.push_back(p->stats.distance_over_d), l.y.push_back(c.ratio);
      l.ylo.push_back(c.ratio_ci.lo), l.yhi.push_back(c.ratio_ci.hi);
    }
    if (!l.x.empty()) f.lines.push_back(std::move(l));
  }
  return f;
}

}  // namespace

ExperimentSection flow_vs_distance_section(const ReportData& data, const ReportOptions& opt) {
  const FlowVsDistanceAnalysis a = analyze_flow_vs_distance(data, opt);
  ExperimentSection s;
  s.title = "Flow rate against the obstruction distance";
  if (a.baseline.empty()) {
    s.paragraphs.push_back(
        "No baseline is defined ([report] baseline = "
        "\"<series label>\"): only the peaks are given.");
  } else if (!a.baseline_found) {
    s.paragraphs.push_back(fmt::format("The baseline series '{}' has no runs in the store: no gains.", a.baseline));
  } else {
    s.paragraphs.push_back(
        fmt::format("J_0 is {} of the baseline series '{}' (no obstruction). For every "
                    "other series and model, each point's "
                    "mean {} is compared to J_0 as the ratio of means with a 95 % "
                    "percentile bootstrap interval; "
                    "\"significantly above\" means the interval lies above 1 AND Welch's "
                    "t-test gives p < 0.05 (both must agree; below likewise). With [report] pairing = \"paired\", where the runs with {} have "
                    "exactly the same replicates at the point and at J_0 (same seeds, so the same particle "
                    "sets), the comparison is paired instead: Fieller's interval of the ratio of paired means, "
                    "whose verdict is the paired t-test's (marked 'paired' in the tables; points.csv "
                    "ratio_method). "
                    "The peak is the point of largest mean {} among the points where every run has it "
                    "(J_paper: the board emptied). At a point where only some runs emptied, the mean and the "
                    "verdict use those runs alone and read high: check the 'all passed' column.",
                    to_string(a.j), a.baseline, to_string(a.j), to_string(a.j), to_string(a.j)));
  }
  TextTable t;
  t.title = "Peak and significant ranges (D/d)";
  t.header = {"series",
              "model",
              "points",
              "peak D/d",
              "J_max /s [95% CI]",
              "J_0 /s [95% CI]",
              "J_max/J_0 [95% CI]",
              "verdict at peak",
              "above J_0 at D/d",
              "below J_0 at D/d"};
  for (const DistanceResult& r : a.results) {
    t.rows.push_back({r.series, model_name(r.model), fmt::format("{}", r.n_points), fmt_num(r.peak_d_over_d, 3),
                      fmt_mean_ci(r.peak), fmt_mean_ci(r.baseline), r.peak_gain ? ratio_text(*r.peak_gain) : "n/a",
                      r.peak_gain ? to_string(r.peak_gain->verdict) : "n/a", ranges_text(r.above),
                      ranges_text(r.below)});
    s.paragraphs.push_back(distance_sentence(r, a.j));
  }
  s.tables.push_back(std::move(t));
  if (a.baseline_found) s.figures.push_back(ratio_figure(data, opt));
  return s;
}

// ---------------------------------------------------------------- clogging

namespace {

std::string regime_text(const RegimeFractions& g) {
  if (g.n == 0) return "n/a";
  return fmt::format("{} (c {:.2f}, i {:.2f}, x {:.2f})", g.label, g.continuous, g.intermittent, g.clogged);
}

std::string upper_tail_text(const TailCheck& t) {
  if (!t.tested) return t.n > 0 ? fmt::format("n/a (s >= {}: {} sizes)", t.from, t.n) : "n/a";
  return fmt::format("s >= {}: p = {} ({} sizes)", t.from, fmt_num(t.p_value, 2), t.n);
}

std::vector<std::string> clog_point_row(const ClogSeries& cs, const ClogPoint& c) {
  const PointStatistics& st = c.point->stats;
  const CensoredMean& m = st.avalanches.size;
  const TailCheck& tail = st.avalanches.tail;
  const ClogStatistics& cl = st.clogs;
  return {cs.series,
          model_name(cs.model),
          label_or_single(c.point->point_label),
          fmt_num(c.w_over_d, 3),
          fmt_num(c.w2, 3),
          m.n_uncensored > 0 ? fmt_num(m.mean, 3) + " " + fmt_interval(m.ci95, 3) : "n/a",
          fmt::format("{} ({})", m.n, m.n_censored),
          fmt_num(c.ln_s1, 3) + " " + fmt_ci(c.ln_lo, c.ln_hi, 3),
          tail.tested ? fmt::format("p = {}", fmt_num(tail.p_value, 2)) : "n/a",
          upper_tail_text(st.avalanches.upper_tail),
          fmt_clogs(cl),
          fmt_num(cl.mean_uncensored_s, 3),
          fmt_num(cl.median_uncensored_s, 3),
          fmt_num(cl.fraction_censored, 2),
          cl.tail.valid() ? fmt_num(cl.tail.alpha, 3) + (cl.heavy_tail ? " (heavy)" : "") : "n/a",
          regime_text(st.regime)};
}

// The paper's decomposition J = <s> / (<T_flow> + <T_clog>) next to the rates measured
// directly: a check of the clog and avalanche bookkeeping that can fail.
std::vector<std::string> decomposition_row(const ClogSeries& cs, const ClogPoint& c) {
  const PointStatistics& st = c.point->stats;
  const FlowDecomposition& f = st.decomposition;
  std::vector<std::string> row{cs.series, model_name(cs.model), label_or_single(c.point->point_label),
                               fmt::format("{}", f.n_avalanches), fmt::format("{}", f.n_clogs)};
  for (double v : {f.mean_size, f.tau_s, f.mean_t_flow_s, f.mean_t_clog_s, f.j_cycle, f.j_total})
    row.push_back(f.valid ? fmt_num(v, 4) : "n/a");
  row.push_back(fmt_mean_ci(mean_ci(st.j_mid.t)));
  row.push_back(f.valid ? fmt_num(f.j_flow, 4) : "n/a");
  row.push_back(fmt_mean_ci(mean_ci(st.j_flowing.t)));
  return row;
}

// Points with fewer completed avalanches draw no size distribution (it would be noise).
constexpr std::size_t kMinSizesForDistribution = 20;

// ln P(S >= s) against (s - 1)(-ln q), q = 1 - 1/mean of the completed sizes: a geometric
// law with that mean is the line y = -x exactly, whatever the mean, so every point shares
// one figure and a deviation shows where it is (small sizes: left; tail: right).
PlotLine size_distribution_line(const ClogSeries& cs, const ClogPoint& c) {
  PlotLine l;
  l.label = fmt::format("{} ({}) W/d {}", cs.series, model_name(cs.model), fmt_num(c.w_over_d, 3));
  l.model = cs.model;
  l.style = "markers";
  std::vector<int> sizes = c.point->stats.avalanches.sizes;
  if (sizes.size() < kMinSizesForDistribution) return l;
  const double n = static_cast<double>(sizes.size());
  const double mean = std::accumulate(sizes.begin(), sizes.end(), 0.0) / n;
  if (!(mean > 1)) return l;
  const double rate = -std::log1p(-1.0 / mean);  // -ln q
  std::sort(sizes.begin(), sizes.end());
  for (std::size_t i = 0; i < sizes.size(); ++i) {
    if (i > 0 && sizes[i] == sizes[i - 1]) continue;  // one point per distinct size
    l.x.push_back((sizes[i] - 1) * rate);
    l.y.push_back(std::log((n - static_cast<double>(i)) / n));  // P(S >= s): the sizes from i on
  }
  return l;
}

PlotFigure size_distribution_figure(const CloggingAnalysis& a) {
  PlotFigure f{"avalanche_sizes.png",
               "Avalanche sizes against a geometric law (the line y = -x)",
               "(s - 1) (-ln q),  q = 1 - 1/mean size",
               "ln P(S >= s)",
               {},
               {},
               false};
  double x_max = 0;
  for (const ClogSeries& cs : a.series)
    for (const ClogPoint& c : cs.points) {
      PlotLine l = size_distribution_line(cs, c);
      if (l.x.empty()) continue;
      x_max = std::max(x_max, l.x.back());
      f.lines.push_back(std::move(l));
    }
  if (f.lines.empty()) return f;
  PlotLine law;
  law.label = "geometric law";
  law.style = "curve_fixed";
  law.x = {0.0, x_max};
  law.y = {0.0, -x_max};
  f.lines.push_back(std::move(law));
  return f;
}

// A line through 2 points fits them exactly and has no interval: it is not drawn
// (as the Beverloo fits without degrees of freedom are not).
bool drawn(const LineFit& f) { return f.ok && f.n >= 3; }

std::string fit_note(const LineFit& f) {
  if (!f.ok) return "no fit (fewer than 2 distinct W/d with avalanches)";
  return drawn(f) ? f.weighting : f.weighting + "; not drawn: 2 points leave no degrees of freedom, no intervals";
}

PlotLine clog_fit_curve(const ClogSeries& cs) {
  PlotLine l;
  l.label = fmt::format("{} ({}) fit", cs.series, model_name(cs.model));
  l.group = fmt::format("{} ({})", cs.series, model_name(cs.model));
  l.model = cs.model;
  l.style = "curve";
  if (!drawn(cs.fit)) return l;
  double lo = kNaN, hi = kNaN;
  for (const ClogPoint& c : cs.points)
    if (std::isfinite(c.ln_s1))
      lo = std::isnan(lo) ? c.w2 : std::min(lo, c.w2), hi = std::isnan(hi) ? c.w2 : std::max(hi, c.w2);
  for (double x : {lo, hi}) l.x.push_back(x), l.y.push_back(cs.fit.intercept + cs.fit.slope * x);
  return l;
}

}  // namespace

ExperimentSection clogging_section(const ReportData& data, const ReportOptions&) {
  const CloggingAnalysis a = analyze_clogging(data);
  ExperimentSection s;
  s.title = "Clogging: avalanche size against the gap width";
  s.paragraphs.push_back(
      "<s> is the mean avalanche size (crossings between clogs; each run's "
      "first avalanche, shaped by the initial "
      "packing, is excluded), estimated with censoring (avalanches cut by the "
      "end of a run count as lower bounds: "
      "exponential/geometric MLE, chi-square 95 % interval). ln(<s>+1) is "
      "fitted by a straight line in (W/d)^2 "
      "(weighted by the interval widths), the form expected when <s> grows "
      "like exp(c (W/d)^2). The geometric columns "
      "are goodness-of-fit p-values (Kolmogorov-Smirnov, parametric bootstrap) of the completed avalanche "
      "sizes: of all of them, and of the tail above the mean alone (sizes s >= ceil(<s>), shifted; "
      "the exponential law is a claim about the tail, small avalanches may deviate: Zuriguel et al. "
      "2005); p = 0.001 is the smallest the 1000 resamples can give. The clog durations are those of "
      "completed clogs (Hill exponent alpha < 2: heavy tail). Regime: label "
      "(fractions continuous, intermittent, "
      "clogged).");
  TextTable pts;
  pts.title = "Avalanches and clogs by point";
  pts.header = {"series",
                "model",
                "point",
                "W/d",
                "(W/d)^2",
                "<s> [95% CI]",
                "avalanches (censored)",
                "ln(<s>+1) [95% CI]",
                "geometric law, all sizes",
                "geometric tail, s >= ceil(<s>)",
                "clogs",
                "clog mean s",
                "clog median s",
                "censored",
                "Hill alpha",
                "regime"};
  TextTable fits;
  fits.title = "ln(<s>+1) = a + b (W/d)^2";
  fits.header = {"series", "model", "b [95% CI]", "a [95% CI]", "chi2/dof", "points", "weighting"};
  TextTable decomposition;
  decomposition.title = "J = <s> / (<T_flow> + <T_clog>) against the measured rates";
  decomposition.header = {"series",        "model",     "point",      "avalanches",       "clogs",
                          "<s> (all)",     "tau s",     "<T_flow> s", "<T_clog> s",       "<s>/(<T_flow>+<T_clog>) /s",
                          "J_total /s",    "J_mid /s measured [t 95%]", "1/tau /s",         "J_flowing /s measured [t 95%]"};
  decomposition.notes.push_back(
      "pooled over the point's runs; <s> over all avalanches (first ones included), tau the mean time "
      "between crossings while flowing, T_clog = clog duration - tau (completed clogs). J_total = sum s / "
      "(sum T_flow + sum T_clog) equals the paper's form when every avalanche ends in a completed clog; it "
      "should match J_mid (the rate between the 10 % and 90 % crossings) where the flow is steady, and "
      "1/tau should match J_flowing (crossings per second of flowing time).");
  for (const ClogSeries& cs : a.series) {
    for (const ClogPoint& c : cs.points) {
      pts.rows.push_back(clog_point_row(cs, c));
      decomposition.rows.push_back(decomposition_row(cs, c));
    }
    fits.rows.push_back({cs.series, model_name(cs.model), fmt_num(cs.fit.slope) + " " + fmt_interval(cs.fit.slope_ci),
                         fmt_num(cs.fit.intercept) + " " + fmt_interval(cs.fit.intercept_ci),
                         fmt_num(cs.fit.chi2_per_dof, 3), fmt::format("{}", cs.fit.n),
                         fit_note(cs.fit)});
    s.overlays["clogging.png"].push_back(clog_fit_curve(cs));
  }
  s.tables.push_back(std::move(pts));
  s.tables.push_back(std::move(fits));
  s.tables.push_back(std::move(decomposition));
  PlotFigure sizes = size_distribution_figure(a);
  if (!sizes.lines.empty()) {
    s.paragraphs.push_back(fmt::format(
        "avalanche_sizes.png: the distribution of the completed avalanche sizes of every point with at "
        "least {} of them, scaled so that a geometric law is the line y = -x; points above the line at the "
        "left mean too few small avalanches, a bend at the right a tail unlike the law's.",
        kMinSizesForDistribution));
    s.figures.push_back(std::move(sizes));
  }
  return s;
}

// ---------------------------------------------------------------- models

ExperimentSection models_section(const ReportData& data, const ReportOptions& opt) {
  const ModelsAnalysis a = analyze_models(data, opt);
  ExperimentSection s;
  s.title = "2D against 3D";
  s.paragraphs.push_back(
      fmt::format("For every point run in both models: J_2D/J_3D = mean {} in 2D / mean {} "
                  "in 3D with a 95 % percentile "
                  "bootstrap interval (verdict: 2D significantly above / below 3D). Over "
                  "the {} points with {} defined in both "
                  "models: mean ratio {}, Pearson correlation of the mean J {}, Spearman "
                  "rank correlation (ranking agreement) {}.",
                  to_string(a.j), to_string(a.j), a.n_both, to_string(a.j), fmt_num(a.mean_ratio, 4),
                  fmt_num(a.pearson, 3), fmt_num(a.spearman, 3)));
  TextTable t;
  t.title = "J in 2D and 3D";
  t.header = {"series",  "point",  "J_2D /s [95% CI]", "J_3D /s [95% CI]", "J*_2D", "J*_3D", "J_2D/J_3D [95% CI]",
              "verdict", "Welch p"};
  PlotFigure f{"models_2d_vs_3d.png",
               fmt::format("{}* in 3D against 2D", to_string(a.j)),
               fmt::format("{}* 2D", to_string(a.j)),
               fmt::format("{}* 3D", to_string(a.j)),
               {},
               {},
               true};
  for (const ModelPair& m : a.pairs) {
    t.rows.push_back({m.series, label_or_single(m.point_label), fmt_mean_ci(m.j2d), fmt_mean_ci(m.j3d),
                      fmt_num(m.j2d_star.mean), fmt_num(m.j3d_star.mean), ratio_text(m.ratio),
                      to_string(m.ratio.verdict), fmt_num(m.ratio.welch.p_two_sided, 3)});
    auto it = std::find_if(f.lines.begin(), f.lines.end(), [&](const PlotLine& l) { return l.label == m.series; });
    if (it == f.lines.end()) {
      f.lines.push_back(PlotLine{});
      it = f.lines.end() - 1;
      it->label = m.series;
    }
    if (m.j2d.n == 0 || m.j3d.n == 0) continue;
    it->x.push_back(m.j2d_star.mean), it->y.push_back(m.j3d_star.mean);
    it->xlo.push_back(m.j2d_star.lo), it->xhi.push_back(m.j2d_star.hi);
    it->ylo.push_back(m.j3d_star.lo), it->yhi.push_back(m.j3d_star.hi);
  }
  if (a.pairs.empty()) s.paragraphs.push_back("No point was run in both models.");
  s.tables.push_back(std::move(t));
  s.figures.push_back(std::move(f));
  return s;
}

// ---------------------------------------------------------------- screen_confirm

namespace {

// 1-based rank of `value` among `all` (descending: the highest J is rank 1).
int rank_of(double value, const std::vector<double>& all) {
  return 1 + static_cast<int>(std::count_if(all.begin(), all.end(), [&](double v) { return v > value; }));
}

}  // namespace

ExperimentSection screen_confirm_section(const ReportData& data, const ReportOptions& opt) {
  const ModelsAnalysis a = analyze_models(data, opt);
  ExperimentSection s = models_section(data, opt);
  s.title = "Screen (2D) and confirmation (3D)";
  std::vector<double> screened, confirmed_3d;
  for (const ReportPoint& p : data.points) {
    const MeanCI m = mean_ci(j_stats(p.stats, opt.j).t);
    if (p.model == "2d" && m.n > 0) screened.push_back(m.mean);
  }
  for (const ModelPair& m : a.pairs)
    if (m.j3d.n > 0) confirmed_3d.push_back(m.j3d.mean);
  TextTable t;
  t.title = "Ranks (1 = highest mean J)";
  t.header = {"series",
              "point",
              "rank in the 2D screen",
              "2D J /s [95% CI]",
              "rank among the confirmed, 2D",
              "3D J /s [95% CI]",
              "rank among the confirmed, 3D"};
  std::vector<double> confirmed_2d;
  for (const ModelPair& m : a.pairs)
    if (m.j2d.n > 0 && m.j3d.n > 0) confirmed_2d.push_back(m.j2d.mean);
  for (const ModelPair& m : a.pairs) {
    const bool both = m.j2d.n > 0 && m.j3d.n > 0;
    t.rows.push_back({m.series, label_or_single(m.point_label),
                      m.j2d.n > 0 ? fmt::format("{}", rank_of(m.j2d.mean, screened)) : "n/a",
                      fmt_mean_ci(m.j2d),
                      both ? fmt::format("{}", rank_of(m.j2d.mean, confirmed_2d)) : "n/a",
                      fmt_mean_ci(m.j3d),
                      both ? fmt::format("{}", rank_of(m.j3d.mean, confirmed_3d)) : "n/a"});
  }
  s.paragraphs.insert(s.paragraphs.begin(), fmt::format("{} of the {} points screened in 2D with {} defined were run "
                                                        "in 3D. The Spearman "
                                                        "correlation below says whether 3D keeps the screen's order.",
                                                        a.n_both, screened.size(), to_string(a.j)));
  s.tables.insert(s.tables.begin(), std::move(t));
  return s;
}

}  // namespace gapflow

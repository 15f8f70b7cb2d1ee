// Report tables: number formatting, text and Markdown rendering, the per-point tables and points.csv.
#include "studies/report.hpp"

#include "common/units.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <ostream>

namespace gapflow {

std::string fmt_num(double v, int digits) {
  if (!std::isfinite(v)) return "n/a";
  return fmt::format("{:.{}g}", v, digits);
}

std::string fmt_ci(double lo, double hi, int digits) {
  if (!std::isfinite(lo) || !std::isfinite(hi)) return "n/a";
  return fmt::format("[{}, {}]", fmt_num(lo, digits), fmt_num(hi, digits));
}

std::string fmt_interval(const Interval& i, int digits) { return fmt_ci(i.lo, i.hi, digits); }

std::string fmt_clogs(const ClogStatistics& c) {
  if (c.n_located == 0) return fmt::format("{}", c.n);
  // Clogs located by their front distance alone are in "at gap" or "upstream"; some of them
  // may have leaned on the obstruction, so its count is then a lower bound.
  std::string out = fmt::format("{}: {} at gap, {}{} on obstruction, {} upstream", c.n, c.n_at_gap,
                                c.n_contact_not_measured > 0 ? ">= " : "", c.n_on_obstruction, c.n_upstream);
  if (c.n_contact_not_measured > 0) out += fmt::format(" ({} by front distance only)", c.n_contact_not_measured);
  if (c.n_located < c.n) out += fmt::format(", {} not located", c.n - c.n_located);
  return out;
}

namespace {

std::vector<std::size_t> column_widths(const TextTable& t) {
  std::vector<std::size_t> w(t.header.size(), 0);
  for (std::size_t c = 0; c < t.header.size(); ++c) w[c] = t.header[c].size();
  for (const auto& row : t.rows)
    for (std::size_t c = 0; c < row.size() && c < w.size(); ++c) w[c] = std::max(w[c], row[c].size());
  return w;
}

std::string cell(const std::vector<std::string>& row, std::size_t c) { return c < row.size() ? row[c] : ""; }

// '|' would end a Markdown cell.
std::string md_escape(const std::string& s) {
  std::string out;
  for (char ch : s) out += ch == '|' ? std::string("\\|") : std::string(1, ch);
  return out;
}

}  // namespace

std::string render_text(const TextTable& t) {
  const auto w = column_widths(t);
  std::string out = t.title.empty() ? "" : t.title + "\n";
  auto line = [&](const std::vector<std::string>& row) {
    std::string s;
    for (std::size_t c = 0; c < w.size(); ++c) s += fmt::format("{}{:<{}}", c ? "  " : "", cell(row, c), w[c]);
    s.erase(s.find_last_not_of(' ') + 1);
    return s + "\n";
  };
  out += line(t.header);
  std::size_t total = 0;
  for (std::size_t x : w) total += x + 2;
  out += std::string(total > 2 ? total - 2 : 0, '-') + "\n";
  for (const auto& row : t.rows) out += line(row);
  for (const std::string& n : t.notes) out += "  " + n + "\n";
  return out;
}

std::string render_markdown(const TextTable& t) {
  std::string out = t.title.empty() ? "" : "**" + md_escape(t.title) + "**\n\n";
  auto line = [&](const std::vector<std::string>& row) {
    std::string s = "|";
    for (std::size_t c = 0; c < t.header.size(); ++c) s.append(" ").append(md_escape(cell(row, c))).append(" |");
    return s + "\n";
  };
  out += line(t.header);
  out += "|";
  for (std::size_t c = 0; c < t.header.size(); ++c) out += c == 0 ? " :-- |" : " --: |";
  out += "\n";
  for (const auto& row : t.rows) out += line(row);
  if (!t.notes.empty()) out += "\n";
  for (const std::string& n : t.notes) out += "*" + n + "*\n\n";
  return out;
}

// ---------------------------------------------------------------- per-point tables


std::string fmt_mean_ci(const MeanCI& m, int digits) {
  if (m.n == 0) return "n/a";
  if (m.n == 1) return fmt_num(m.mean, digits) + " (1 run)";  // no interval from one value
  return fmt_num(m.mean, digits) + " " + fmt_ci(m.lo, m.hi, digits);
}

namespace {

std::string point_name(const ReportPoint& p) { return p.point_label.empty() ? "(single point)" : p.point_label; }

// The chosen J three ways, side by side (the paper drops runs beyond 2 sigma; we
// never do it silently): mean with its bootstrap interval, median, 2-sigma-rule mean.
std::vector<std::string> j_three_ways(const SampleStatistics& s) {
  if (s.t.n == 0) return {"n/a", "n/a", "n/a"};
  const std::string mean = s.t.n == 1 ? fmt_num(s.t.mean, 4) + " (1 run)"
                                      : fmt_num(s.t.mean, 4) + " " + fmt_interval(s.bootstrap, 4);
  const std::string clipped =
      fmt_num(s.clipped.kept.mean, 4) + (s.clipped.dropped > 0 ? fmt::format(" ({} dropped)", s.clipped.dropped) : "");
  return {mean, fmt_num(s.median, 4), clipped};
}

std::vector<JKind> other_kinds(JKind j) {
  std::vector<JKind> out;
  for (JKind k : {JKind::paper, JKind::flowing, JKind::mid})
    if (k != j) out.push_back(k);
  return out;
}

bool any_steady(const ReportData& data) {
  for (const ReportPoint& p : data.points)
    if (p.steady) return true;
  return false;
}

// J_steady of the re-injected runs, pooled (studies/steady_analysis.hpp).
std::string fmt_steady(const std::optional<SteadyPointStatistics>& st) {
  if (!st || st->n_valid == 0) return "n/a";
  Interval ci = st->interval();
  return fmt_num(st->j_per_s, 4) + " " + fmt_interval(ci, 4) +
         (st->n_autocorrelated + st->n_transient_at_limit > 0 ? " (run longer)" : "");
}

std::vector<std::string> point_row(const ReportPoint& p, JKind j, bool with_baseline, bool with_steady) {
  const PointStatistics& s = p.stats;
  const CensoredMean& av = s.avalanches.size;
  std::vector<std::string> row{
      point_name(p),
      fmt_num(s.w_over_d, 3),
      fmt_num(s.distance_over_d, 3),
      fmt::format("{}", s.n_runs),
      fmt_num(s.all_passed_fraction, 3),
  };
  for (std::string& cell : j_three_ways(j_stats(s, j))) row.push_back(std::move(cell));
  for (JKind k : other_kinds(j)) row.push_back(fmt_mean_ci(mean_ci(j_stats(s, k).t)));
  row.insert(row.end(), {
                            fmt_mean_ci(j_star(s, j)),
                            av.n_uncensored > 0 ? fmt_num(av.mean, 3) + " " + fmt_interval(av.ci95, 3) : "n/a",
                            fmt_clogs(s.clogs),
                            s.regime.label,
                        });
  if (with_steady) row.push_back(fmt_steady(p.steady));
  if (with_baseline) {
    if (p.vs_baseline && std::isfinite(p.vs_baseline->ratio)) {
      const RatioComparison& r = *p.vs_baseline;
      row.push_back(fmt_num(r.ratio, 3) + " " + fmt_interval(r.ratio_ci, 3) + (r.paired ? " paired" : ""));
      row.push_back(to_string(r.verdict));
    } else {
      row.push_back("n/a");
      row.push_back(p.vs_baseline ? to_string(p.vs_baseline->verdict) : "");
    }
  }
  return row;
}

std::vector<std::string> point_header(JKind j, bool with_baseline, bool with_steady) {
  const std::string name = to_string(j);
  std::vector<std::string> h{"point",
                             "W/d",
                             "D/d",
                             "runs",
                             "all passed",
                             name + " /s mean [bootstrap 95%]",
                             name + " median",
                             name + " 2-sigma rule",
                             };
  for (JKind k : other_kinds(j)) h.push_back(std::string(to_string(k)) + " /s [t 95%]");
  h.insert(h.end(), {name + "* [t 95%]", "<s> [95% CI]", "clogs", "regime"});
  if (with_steady) h.push_back("steady /s [batch means 95%]");
  if (with_baseline) h.insert(h.end(), {"J/J_0 [95% CI]", "verdict"});
  return h;
}

}  // namespace

std::vector<TextTable> point_tables(const ReportData& data, JKind j) {
  const bool with_baseline = !data.study.report.baseline.empty();
  std::vector<TextTable> out;
  for (const auto& [series, model] : series_models(data)) {
    TextTable t;
    t.title = fmt::format("series '{}', model {}", series, model);
    t.header = point_header(j, with_baseline, any_steady(data));
    const bool ref = !data.study.report.baseline.empty() && series == data.study.report.baseline;
    for (const ReportPoint* p : points_of(data, series, model))
      t.rows.push_back(point_row(*p, j, with_baseline && !ref, any_steady(data)));
    if (ref) t.notes.push_back("this series is the baseline (J_0)");
    out.push_back(std::move(t));
  }
  return out;
}

// ---------------------------------------------------------------- points.csv

namespace {

std::string csv_text(const std::string& v) {
  if (v.find_first_of(",\"\r\n") == std::string::npos) return v;
  std::string q = "\"";
  for (char ch : v) q += ch == '"' ? std::string("\"\"") : std::string(1, ch);
  return q + "\"";
}

// Shortest text that reads back exactly; empty for NaN and infinities.
std::string csv_num(double v) { return std::isfinite(v) ? fmt::format("{}", v) : std::string(); }

class CsvRow {
 public:
  CsvRow(std::vector<std::string>& header, bool header_pass) : header_(header), header_pass_(header_pass) {}
  void text(const std::string& name, const std::string& v) { add(name, csv_text(v)); }
  void num(const std::string& name, double v) { add(name, csv_num(v)); }
  void count(const std::string& name, std::size_t v) { add(name, std::to_string(v)); }
  const std::vector<std::string>& fields() const { return fields_; }

 private:
  void add(const std::string& name, std::string v) {
    if (header_pass_) header_.push_back(name);
    fields_.push_back(std::move(v));
  }
  std::vector<std::string>& header_;
  bool header_pass_;
  std::vector<std::string> fields_;
};

void j_columns(CsvRow& row, const std::string& name, const SampleStatistics& s, double star) {
  const MeanCI m = mean_ci(s.t);
  row.count(name + "_n", s.t.n);
  row.num(name + "_mean", m.mean);
  row.num(name + "_t_lo", m.lo);
  row.num(name + "_t_hi", m.hi);
  row.num(name + "_boot_lo", s.bootstrap.lo);
  row.num(name + "_boot_hi", s.bootstrap.hi);
  row.num(name + "_median", s.median);
  row.num(name + "_clipped_mean", s.clipped.kept.n ? s.clipped.kept.mean : kNaN);
  row.count(name + "_n_dropped", s.clipped.dropped);
  row.num(name + "_star_mean", m.mean * star);
  row.num(name + "_star_t_lo", m.lo * star);
  row.num(name + "_star_t_hi", m.hi * star);
}

void avalanche_and_clog_columns(CsvRow& row, const PointStatistics& s) {
  const AvalancheStatistics& a = s.avalanches;
  row.num("aval_mean", a.size.mean);
  row.num("aval_lo", a.size.ci95.lo);
  row.num("aval_hi", a.size.ci95.hi);
  row.count("aval_n", a.size.n);
  row.count("aval_n_censored", a.size.n_censored);
  row.num("aval_tail_p", a.tail.tested ? a.tail.p_value : kNaN);
  row.text("aval_tail_law", a.tail.law);
  row.num("aval_upper_tail_from", a.upper_tail.n > 0 ? a.upper_tail.from : kNaN);
  row.count("aval_upper_tail_n", a.upper_tail.n);
  row.num("aval_upper_tail_p", a.upper_tail.tested ? a.upper_tail.p_value : kNaN);
  row.count("clog_n", s.clogs.n);
  row.num("clog_mean_s", s.clogs.mean_uncensored_s);
  row.num("clog_median_s", s.clogs.median_uncensored_s);
  row.num("clog_censored_fraction", s.clogs.fraction_censored);
  row.num("clog_hill_alpha", s.clogs.tail.valid() ? s.clogs.tail.alpha : kNaN);
  row.count("clog_located_n", s.clogs.n_located);
  // The sites are counts over the located clogs: blank where clogs were stored without a
  // location (a 0 would read as "none there"); on the obstruction also blank where some
  // clog was located by its front distance alone.
  const ClogStatistics& c = s.clogs;
  const bool unlocated = c.n_located == 0 && c.n > 0;
  auto site = [&](std::size_t k, bool known) { return known ? static_cast<double>(k) : kNaN; };
  row.num("clog_at_gap_n", site(c.n_at_gap, !unlocated));
  row.num("clog_on_obstruction_n", site(c.n_on_obstruction, !unlocated && c.n_contact_not_measured == 0));
  row.num("clog_upstream_n", site(c.n_upstream, !unlocated));
  row.num("clog_median_front_d", s.clogs.median_front_d);
}

void regime_and_decomposition_columns(CsvRow& row, const PointStatistics& s) {
  row.num("regime_continuous", s.regime.continuous);
  row.num("regime_intermittent", s.regime.intermittent);
  row.num("regime_clogged", s.regime.clogged);
  row.text("regime_label", s.regime.label);
  const FlowDecomposition& f = s.decomposition;
  row.num("decomp_tau_s", f.tau_s);
  row.num("decomp_mean_size", f.mean_size);
  row.num("decomp_t_flow_s", f.mean_t_flow_s);
  row.num("decomp_t_clog_s", f.mean_t_clog_s);
  row.num("decomp_j_flow", f.j_flow);
  row.num("decomp_j_cycle", f.j_cycle);
  row.num("decomp_j_total", f.j_total);
  row.num("mean_wall_time_s", s.mean_wall_time_s);
}

void steady_columns(CsvRow& row, const ReportPoint& p) {
  const SteadyPointStatistics* st = p.steady ? &*p.steady : nullptr;
  row.count("J_steady_runs", st ? st->n_valid : 0);
  row.num("J_steady_mean", st ? st->j_per_s : kNaN);
  row.num("J_steady_lo", st ? st->interval().lo : kNaN);
  row.num("J_steady_hi", st ? st->interval().hi : kNaN);
  row.num("J_steady_truncation_s", st ? st->mean_truncation_s : kNaN);
  row.num("J_steady_window_s", st ? st->total_window_s : kNaN);
}

void baseline_columns(CsvRow& row, const ReportPoint& p) {
  const RatioComparison* r = p.vs_baseline ? &*p.vs_baseline : nullptr;
  row.text("baseline", p.baseline_label);
  row.num("ratio", r ? r->ratio : kNaN);
  row.num("ratio_lo", r ? r->ratio_ci.lo : kNaN);
  row.num("ratio_hi", r ? r->ratio_ci.hi : kNaN);
  row.num("welch_p", r ? r->welch.p_two_sided : kNaN);
  row.text("verdict", r ? to_string(r->verdict) : "");
  // Appended last: the columns before keep their places. paired: Fieller + paired t (studies/paired.hpp).
  row.text("ratio_method", r ? (r->paired ? "paired" : "unpaired") : "");
  row.num("paired_t_p", r && r->paired ? r->paired_t.p_two_sided : kNaN);
  row.num("pair_correlation", r && r->paired ? r->correlation : kNaN);
}

CsvRow csv_row(const ReportData& data, const ReportPoint& p, std::vector<std::string>& header, bool header_pass) {
  CsvRow row(header, header_pass);
  row.text("series", p.series);
  row.text("model", p.model);
  row.count("point", static_cast<std::size_t>(p.point));
  row.text("point_label", p.point_label);
  for (const std::string& key : data.axis_keys) {
    const AxisEntry* a = p.axis(key);
    row.text(key, a ? a->text : "");
  }
  const PointStatistics& s = p.stats;
  row.num("W_over_d", s.w_over_d);
  row.num("D_over_d", s.distance_over_d);
  row.num("d_mm", p.d_mm);
  row.count("n_runs", s.n_runs);
  row.num("all_passed_fraction", s.all_passed_fraction);
  row.num("mean_passed_fraction", s.mean_passed_fraction);  // how far a board that never emptied got
  j_columns(row, "J_paper", s.j_paper, s.j_star_factor);
  j_columns(row, "J_flowing", s.j_flowing, s.j_star_factor);
  j_columns(row, "J_mid", s.j_mid, s.j_star_factor);
  avalanche_and_clog_columns(row, s);
  regime_and_decomposition_columns(row, s);
  if (any_steady(data)) steady_columns(row, p);
  if (!data.study.report.baseline.empty()) baseline_columns(row, p);
  return row;
}

void write_line(std::ostream& out, const std::vector<std::string>& fields) {
  for (std::size_t i = 0; i < fields.size(); ++i) out << (i ? "," : "") << fields[i];
  out << "\n";
}

}  // namespace

void write_points_csv(std::ostream& out, const ReportData& data) {
  std::vector<std::string> header;
  bool first = true;
  std::vector<std::vector<std::string>> rows;
  for (const ReportPoint& p : data.points) {
    rows.push_back(csv_row(data, p, header, first).fields());
    first = false;
  }
  if (first) csv_row(data, ReportPoint{}, header, true);  // no points: still the header
  std::vector<std::string> quoted;
  for (const std::string& h : header) quoted.push_back(csv_text(h));
  write_line(out, quoted);
  for (const auto& r : rows) write_line(out, r);
}

}  // namespace gapflow

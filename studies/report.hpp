// The study report: from a results store (and optionally its study file) to
//   points.csv   one row per (series, model, point), every statistic side by side
//   stdout       the same as human-readable tables, per series and model
//   *.png        plots, drawn by studies/plot_study.py from a JSON spec (plots.json)
//   report.md    what was run, the tables, the plots and the experiment analyses
//
// Every number comes from the store; the C++ side decides what to draw and the Python
// script only draws it, so the logic is tested here and the script stays dumb.
//
// The study file's optional [report] table chooses the experiment analyses (the same
// schema as the study loader's ReportDef, studies/study.hpp):
//   [report]
//   kind = "flow_vs_distance"  # or a list of: flow_vs_gap, flow_vs_distance, clogging,
//                              # models, screen_confirm; absent: the generic outputs only
//   baseline = "none"          # series label of the reference (J ratio + verdict per point)
//   j = "paper"                # "paper" | "flowing" | "mid": the J the analyses use
//   fit_w_min = 2.0            # flow_vs_gap: W/d range of the Beverloo fits (inclusive)
//   fit_w_max = 12.0
//   pairing = "unpaired"       # or "paired": J/J_0 paired by replicate where the replicate sets match
// Files: report.cpp (options, collection), report_tables.cpp (tables, CSV),
// report_experiments.cpp (the analyses), report_sections.cpp (their text, tables, plots),
// report_plots.cpp (plot spec, running Python), report_output.cpp (report.md, make_report).
#pragma once

#include "common/fits.hpp"
#include "studies/analysis.hpp"
#include "studies/steady_analysis.hpp"
#include "studies/store.hpp"
#include "studies/study.hpp"

#include <filesystem>
#include <iosfwd>
#include <limits>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace gapflow {

// ---------------------------------------------------------------- options and study info

enum class ReportKind { flow_vs_gap, flow_vs_distance, clogging, models, screen_confirm };
const char* to_string(ReportKind k);

struct ReportOptions {
  std::vector<ReportKind> kinds;  // in the order written; empty = generic outputs only
  std::string baseline;           // series label; "" = no baseline
  JKind j = JKind::paper;
  Pairing pairing = Pairing::never;  // "paired": J/J_0 paired by replicate where the sets match (studies/paired.hpp)
  double fit_w_min = -std::numeric_limits<double>::infinity();
  double fit_w_max = std::numeric_limits<double>::infinity();
};

// What the report needs from a study file. [study] and [[series]] are read
// leniently (the study loader validates them); [report] strictly: an unknown
// key or bad value is a ScenarioError with file:line:column.
struct StudyInfo {
  std::filesystem::path file;  // "" when no study file was given
  std::string recorded_at;     // set when the file's text is the copy recorded in the store (UTC)
  std::string name, description;
  std::optional<int> replicates;
  std::vector<std::string> models;        // as written ("2d", "3d")
  std::vector<std::string> series_order;  // labels in file order
  ReportOptions report;
  bool screen = false;  // the file has a [screen] table: the report adds the screen's map (studies/report_screen.cpp)
};
StudyInfo read_study_info(const std::filesystem::path& file);
StudyInfo parse_study_info(std::string_view text, std::string_view source_name);

// ---------------------------------------------------------------- points

struct AxisEntry {
  std::string key;       // dotted scenario key
  std::string text;      // the value as stored in axes_json (strings without quotes)
  double number = kNaN;  // NaN unless numeric
};
// The flat JSON object of JobIdentity::axes_json, in its order. Throws std::runtime_error if malformed.
std::vector<AxisEntry> parse_axes_json(std::string_view json);

struct ReportPoint {
  std::string series, model;
  int point = 0;
  std::string point_label;
  std::vector<AxisEntry> axes;
  double d_mm = kNaN;  // nominal diameter of the first run
  PointStatistics stats;
  std::optional<SteadyPointStatistics> steady;  // when its runs re-injected (studies/steady_analysis.hpp)
  // Against the baseline series (when one is defined and matches; see baseline_for).
  std::optional<RatioComparison> vs_baseline;
  std::string baseline_label;  // "<series> <point label>" of the reference point

  const AxisEntry* axis(std::string_view key) const;
};

struct ReportData {
  StudyInfo study;
  std::vector<std::string> axis_keys;  // every swept key, first-seen order
  std::vector<ReportPoint> points;     // series (study file order, else alphabetical), model, point
  std::size_t n_runs = 0;
  double total_wall_s = 0, total_sim_s = 0;
  std::map<std::string, std::size_t> code_versions;  // version -> runs
  std::vector<std::string> models;
  std::size_t min_replicates = 0,
              max_replicates = 0;  // runs per point and model
  std::string first_finished, last_finished;
};

ReportData collect_report_data(const std::vector<StoredRun>& runs, StudyInfo info, const AnalysisOptions& opt = {});

// The reference point of `p`: the baseline series' point in the same model with
// the same W/d (the only one, when the baseline series has one point per model). nullptr if none.
const ReportPoint* baseline_for(const ReportData& data, const ReportPoint& p);
bool is_baseline(const ReportData& data, const ReportPoint& p);

// j_stats, j_values: studies/analysis.hpp.

// A mean with its Student-t 95 % interval; NaN where undefined (n = 0: all; n = 1: the interval).
struct MeanCI {
  std::size_t n = 0;
  double mean = kNaN, lo = kNaN, hi = kNaN;
  MeanCI scaled(double f) const { return {n, mean * f, lo * f, hi * f}; }
};
MeanCI mean_ci(const Summary& s);
MeanCI j_star(const PointStatistics& s, JKind k);  // J* = J sqrt(d/g)

// What a series is plotted against: W/d for gap sweeps, D/d for distance
// sweeps, else the raw first numeric axis ("" when the series has no numeric axis).
struct XAxis {
  std::string name;  // "W/d", "D/d" or the dotted key
  std::string key;   // the swept key it comes from
  bool valid() const { return !name.empty(); }
};
XAxis x_axis_of(const ReportData& data, const std::string& series);
double x_value(const ReportPoint& p, const XAxis& x);

// Points of one series and model, in point order.
std::vector<const ReportPoint*> points_of(const ReportData& data, const std::string& series, const std::string& model);
// The point of largest mean J among those where every run has J (a point where only some
// runs emptied would be ranked by its lucky runs alone); nullptr when none has.
const ReportPoint* best_point(const std::vector<const ReportPoint*>& points, JKind j);
// (series, model) pairs in report order.
std::vector<std::pair<std::string, std::string>> series_models(const ReportData& data);

// ---------------------------------------------------------------- tables and formatting

struct TextTable {
  std::string title;
  std::vector<std::string> header;
  std::vector<std::vector<std::string>> rows;
  std::vector<std::string> notes;  // printed under the table
};
std::string render_text(const TextTable& t);
std::string render_markdown(const TextTable& t);

std::string fmt_num(double v, int digits = 4);             // "n/a" for NaN
std::string fmt_ci(double lo, double hi, int digits = 4);  // "[lo, hi]" or "n/a"
std::string fmt_interval(const Interval& i, int digits = 4);
std::string fmt_mean_ci(const MeanCI& m,
                        int digits = 4);  // "mean [lo, hi]", "mean (1 run)" or "n/a"
// "n", or "n: g at gap, u upstream" where the clogs' fronts were measured.
std::string fmt_clogs(const ClogStatistics& c);

// Per series and model: the points with the main statistics.
std::vector<TextTable> point_tables(const ReportData& data, JKind j);
// points.csv (header + one row per point; NaN = empty field).
void write_points_csv(std::ostream& out, const ReportData& data);

// ---------------------------------------------------------------- plots

struct PlotLine {
  std::string label;
  std::string model;  // "2d" | "3d" | "": marker and line style
  // "errorbar" (markers + CI, joined), "markers" (the same, not joined: data
  // under a fit), "curve" / "curve_fixed" (a fitted line, solid / dotted)
  std::string style = "errorbar";
  std::vector<double> x, y, ylo, yhi, xlo, xhi;  // xlo/xhi optional (empty)
  std::string group;                             // lines of one group share a colour (data and its fit); ""
                                                 // = the label
};
struct PlotBand {
  std::string label, model;
  double y = kNaN, lo = kNaN, hi = kNaN;
};
struct PlotFigure {
  std::string file;  // PNG name in the output folder
  std::string title, xlabel, ylabel;
  std::vector<PlotLine> lines;
  std::vector<PlotBand> bands;
  bool identity_line = false;
};
std::string plot_spec_json(const std::vector<PlotFigure>& figures);

// J* against each series' x axis (one figure per x quantity), baseline bands;
// the share discharged against the same axes when some run did not empty the board;
// the clogging plot ln(<s>+1) vs (W/d)^2 when avalanche data exist.
std::vector<PlotFigure> generic_figures(const ReportData& data, JKind j);
std::string j_star_figure_file(const std::string& x_name);
// passed/N when the run ended, per series and model (drawn when some run left spheres upstream).
std::string discharge_figure_file(const std::string& x_name);

// A Python 3 interpreter with matplotlib: $GAPFLOW_PYTHON, python3 on PATH, /usr/bin/python3.
std::optional<std::string> find_python_with_matplotlib();
// Path of studies/plot_study.py ($GAPFLOW_PLOT_SCRIPT overrides).
std::filesystem::path plot_script_path();
// Run a program (no shell); its exit code, or -1 when it could not be started.
int run_program(const std::vector<std::string>& argv, const std::filesystem::path& log);

// ---------------------------------------------------------------- experiment analyses

// flow_vs_gap: J* = C (W/d - k)^beta per series and model, free beta and beta = 3/2.
struct GapFit {
  std::string series, model;
  BeverlooFit free_beta, fixed_beta;
};
struct FlowVsGapAnalysis {
  JKind j = JKind::paper;
  std::vector<GapFit> fits;
};
FlowVsGapAnalysis analyze_flow_vs_gap(const ReportData& data, const ReportOptions& opt);

// flow_vs_distance: peak and significant ranges against the baseline, per series and model.
struct DistanceRange {
  double from = kNaN,
         to = kNaN;  // D/d of the first and last point of a contiguous run
  std::size_t n_points = 0;
};
struct DistanceResult {
  std::string series, model;
  std::size_t n_points = 0, n_compared = 0;
  MeanCI baseline;  // J of the reference (of the peak's reference point)
  std::string peak_label;
  double peak_d_over_d = kNaN;
  MeanCI peak;                               // J at the peak
  std::optional<RatioComparison> peak_gain;  // J_max / J_0
  std::vector<DistanceRange> above,
      below;  // verdict significantly above / below
};
struct FlowVsDistanceAnalysis {
  JKind j = JKind::paper;
  std::string baseline;
  bool baseline_found = false;
  std::vector<DistanceResult> results;
};
FlowVsDistanceAnalysis analyze_flow_vs_distance(const ReportData& data, const ReportOptions& opt);

// clogging: <s> vs (W/d)^2 and ln(<s>+1) = a + b (W/d)^2.
struct LineFit {
  bool ok = false;
  std::size_t n = 0;
  double slope = kNaN, intercept = kNaN;
  Interval slope_ci, intercept_ci;  // 95 %, Student t with n - 2 dof
  double chi2_per_dof = kNaN;       // weighted: chi^2/dof; unweighted: residual variance
  std::string weighting;            // "interval widths" or "unweighted"
};
// Least squares of y on x; weighted by 1/se^2 when every se > 0 (intervals scaled by
// max(1, chi^2/dof), as fit_beverloo), else unweighted. The line needs 2 distinct x, the
// intervals 3 points.
LineFit fit_line(const std::vector<double>& x, const std::vector<double>& y, const std::vector<double>& se = {});

struct ClogPoint {
  const ReportPoint* point = nullptr;
  double w_over_d = kNaN, w2 = kNaN;
  double ln_s1 = kNaN, ln_lo = kNaN, ln_hi = kNaN;  // ln(<s>+1) and its interval
};
struct ClogSeries {
  std::string series, model;
  std::vector<ClogPoint> points;  // sorted by W/d
  LineFit fit;                    // ln(<s>+1) on (W/d)^2
};
struct CloggingAnalysis {
  std::vector<ClogSeries> series;
};
CloggingAnalysis analyze_clogging(const ReportData& data);

// models: J_2D / J_3D for every point run in both models.
struct ModelPair {
  std::string series, point_label;
  int point = 0;
  MeanCI j2d, j3d;            // J (1/s)
  MeanCI j2d_star, j3d_star;  // J*
  RatioComparison ratio;      // mean J_2D / mean J_3D
};
struct ModelsAnalysis {
  JKind j = JKind::paper;
  std::vector<ModelPair> pairs;
  double mean_ratio = kNaN;  // mean over points of the ratios
  double pearson = kNaN;     // correlation of mean J over points
  double spearman = kNaN;    // rank correlation (ranking agreement)
  std::size_t n_both = 0;    // points with J defined in both models
};
ModelsAnalysis analyze_models(const ReportData& data, const ReportOptions& opt);

double pearson_correlation(const std::vector<double>& a, const std::vector<double>& b);
double spearman_correlation(const std::vector<double>& a, const std::vector<double>& b);

// An analysis as it goes into the report: text, tables, new figures and curves
// drawn onto generic figures (keyed by figure file).
struct ExperimentSection {
  std::string title;
  std::vector<std::string> paragraphs;  // Markdown
  std::vector<TextTable> tables;
  std::vector<PlotFigure> figures;
  std::map<std::string, std::vector<PlotLine>> overlays;
};
ExperimentSection flow_vs_gap_section(const ReportData& data, const ReportOptions& opt);
ExperimentSection flow_vs_distance_section(const ReportData& data, const ReportOptions& opt);
ExperimentSection clogging_section(const ReportData& data, const ReportOptions& opt);
ExperimentSection models_section(const ReportData& data, const ReportOptions& opt);
// screen_confirm: the models comparison read as "did the 3D confirmation keep the 2D screen's ranking".
ExperimentSection screen_confirm_section(const ReportData& data, const ReportOptions& opt);
// A [screen] study's section: the racing decisions, the final J/J_0 on confirmation runs only,
// the budget against a fixed grid, and one heat map per gap (Cairo PNGs written to out_dir).
ExperimentSection screen_section(const StudyDef& study, const std::vector<StoredRun>& runs,
                                 const std::filesystem::path& out_dir, bool plots);
struct ReportRequest;
// The same from the report's request: the study file given, else the one recorded in the store;
// a section saying why when the grid cannot be rebuilt (e.g. scenario paths that do not resolve).
ExperimentSection screen_report_section(const ReportRequest& request, const std::filesystem::path& db,
                                        const std::vector<StoredRun>& runs, const std::filesystem::path& out_dir,
                                        std::ostream& log);
// One section per opt.kinds entry, in order.
std::vector<ExperimentSection> experiment_sections(const ReportData& data, const ReportOptions& opt);

// ---------------------------------------------------------------- the whole report

struct ReportRequest {
  std::filesystem::path results;               // runs.sqlite or its folder
  std::optional<std::filesystem::path> study;  // study file
  std::optional<std::filesystem::path> out;    // default: the store's folder
  bool plots = true;
  bool snapshots = true;  // one re-simulated top view per point class (studies/report_snapshots.hpp)
  bool quick = false;     // the store holds the study's --quick variant (a screen's grid is thinned)
  // --compare MODEL=STORE: that model's runs from another store (of one study, with the same
  // series and point grid) join the report as if run here, e.g. the 3D runs a 2D-only re-run is
  // compared with; the store given first must hold none of that model.
  struct Compare {
    std::string model;             // "2d" | "3d"
    std::filesystem::path results;  // runs.sqlite or its folder
  };
  std::optional<Compare> compare;
  std::optional<JKind> j;  // --j: the flow rate the analyses use, instead of the study's [report] j
};
// --compare: where two study files (TOML text; sources for error messages) fix different
// settings for the series they share, one line each ("" differences: the same). The [study]
// set and, per common series, the scenario file name and set are compared; [per_model] sets
// are one model's and are not (studies/report_compare.cpp).
std::vector<std::string> study_setting_differences(std::string_view own_text, const std::string& own_source,
                                                   std::string_view other_text, const std::string& other_source);

// The command that regenerates the report (paths as given).
std::string regenerate_command(const ReportRequest& r);

struct ReportOutcome {
  std::filesystem::path out_dir, points_csv, markdown;
  std::vector<std::filesystem::path> pngs;  // written
  std::string plot_warning;                 // why plots are missing ("" when drawn)
  std::vector<std::filesystem::path> snapshots;  // written
  std::string snapshot_warning;                  // why snapshots are missing ("" when drawn or none wanted)
  std::size_t n_points = 0, n_runs = 0;
};

struct MarkdownInput {
  const ReportData* data = nullptr;
  std::vector<TextTable> tables;
  std::vector<ExperimentSection> experiments;
  std::vector<PlotFigure> figures;  // the generic ones (experiment curves drawn in)
  std::vector<std::string> pngs;    // file names of the plots actually written
  std::string plot_warning;
  std::string snapshots;  // the "Snapshots" section (snapshots_markdown), "" = none
  std::string command;
  std::string compare_note;  // where --compare's runs came from ("" = none)
};
std::string render_report_markdown(const MarkdownInput& in);

// Load, analyse, write points.csv, plots and report.md; print the tables to
// `out`, warnings to `log`. Throws std::invalid_argument for a missing store or
// an empty one, ScenarioError for a bad study file.
ReportOutcome make_report(const ReportRequest& request, std::ostream& out, std::ostream& log);
// The analysed points alone (what make_report starts from; e.g. `gapflow report --pairing`).
ReportData load_report_data(const ReportRequest& request, std::ostream& log);

}  // namespace gapflow

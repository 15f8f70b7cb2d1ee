// `gapflow report`: the tiny study end to end (points.csv, report.md, PNGs),
// and the experiment analyses on hand-built stored runs whose answers are known.
#include "studies/jobs.hpp"
#include "studies/report.hpp"
#include "studies/report_snapshots.hpp"
#include "studies/runner.hpp"
#include "studies/store.hpp"
#include "studies/study.hpp"
#include "tests/test_support.hpp"
#include "view/top_view.hpp"

#include <cairo.h>

#include <fmt/format.h>
#include <gtest/gtest.h>
#include <sqlite3.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <sstream>
#include <unistd.h>

using namespace gapflow;
using gapflow::testing::source_path;
namespace fs = std::filesystem;

namespace {

// ------------------------------------------------------------------ helpers

// A fresh folder per test (tests/test_support.hpp), named after this file's subject.
struct TempDir : gapflow::testing::TempDir {
  TempDir() : gapflow::testing::TempDir("gapflow-report") {}
};

std::string read_text(const fs::path& p) {
  std::ifstream in(p);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

void write_text(const fs::path& p, const std::string& text) { std::ofstream(p) << text; }

// CSV split on commas outside quotes (enough for points.csv).
std::vector<std::string> csv_fields(const std::string& line) {
  std::vector<std::string> out(1);
  bool quoted = false;
  for (char c : line) {
    if (c == '"')
      quoted = !quoted;
    else if (c == ',' && !quoted)
      out.emplace_back();
    else
      out.back() += c;
  }
  return out;
}

struct Csv {
  std::vector<std::string> header;
  std::vector<std::vector<std::string>> rows;
  std::size_t column(const std::string& name) const {
    auto it = std::find(header.begin(), header.end(), name);
    EXPECT_NE(it, header.end()) << "no column " << name;
    return static_cast<std::size_t>(it - header.begin());
  }
  std::string at(std::size_t row, const std::string& name) const { return rows.at(row).at(column(name)); }
};

Csv read_csv(const fs::path& p) {
  std::istringstream in(read_text(p));
  Csv c;
  std::string line;
  if (std::getline(in, line)) c.header = csv_fields(line);
  while (std::getline(in, line)) c.rows.push_back(csv_fields(line));
  return c;
}

// The tiny study (12 runs of 60 spheres, ~0.2 s each) into `db`.
void run_tiny(const fs::path& db) {
  Store store(db);
  RunnerOptions o;
  o.workers = 2;
  const RunnerSummary s = run_jobs(expand_jobs(load_study(source_path("studies/examples/tiny.toml"))), store, o);
  ASSERT_EQ(s.done_now, 12);
  ASSERT_TRUE(s.failed.empty());
}

// A stored run built by hand: J_paper = j (J_flowing, J_mid proportional), or
// no J at all when `clogged` (the run never passed every particle).
RunRecord synthetic_run(const std::string& model, double j, double distance_mm, int replicate, bool clogged = false) {
  RunRecord r;
  r.model = model;
  r.scenario_name = "synthetic";
  r.replicate = replicate;
  r.diameter_m = 0.00775, r.gap_m = 0.033, r.distance_m = distance_mm * 1e-3, r.incline_rad = 0.1396;
  r.particles = 100;
  r.passed = clogged ? 40 : 100;
  r.sim_time_s = clogged ? 30 : 100 / j;
  r.wall_time_s = 0.25;
  r.end_reason = clogged ? EndReason::permanent_clog : EndReason::all_passed;
  r.regime = clogged ? Regime::clogged : Regime::continuous;
  if (!clogged) r.j_paper = j, r.j_flowing = 1.1 * j, r.j_mid = 1.05 * j;
  return r;
}

class SyntheticStore {
 public:
  // Keys count from first_key: a second SyntheticStore on the same file needs its own range.
  explicit SyntheticStore(const fs::path& db, std::string study = "synthetic", int first_key = 0)
      : store_(db), study_(std::move(study)), counter_(first_key) {}
  // `values` replicates of one point; axes_json built from the distance when given.
  void add_point(const std::string& series, const std::string& model, int point, std::optional<double> distance_mm,
                 const std::vector<double>& values, bool clogged = false) {
    for (std::size_t i = 0; i < values.size(); ++i) {
      JobIdentity id;
      id.key = fmt::format("{:016x}", ++counter_);
      id.study = study_;
      id.series = series;
      id.point = point;
      id.model = model;
      id.replicate = static_cast<int>(i);
      id.point_label = distance_mm ? fmt::format("obstruction.distance_mm={}", *distance_mm) : "";
      id.axes_json = distance_mm ? fmt::format("{{\"obstruction.distance_mm\":{}}}", *distance_mm) : "{}";
      store_.put(id, synthetic_run(model, values[i], distance_mm.value_or(0), id.replicate, clogged));
    }
  }
  std::vector<StoredRun> load() const { return store_.load(); }

 private:
  Store store_;
  std::string study_;
  int counter_ = 0;
};

// Six replicates around `mean` (sd ~ 0.19): a small, fixed scatter so bootstrap intervals are tight.
std::vector<double> around(double mean) {
  return {mean - 0.25, mean - 0.15, mean - 0.05, mean + 0.05, mean + 0.15, mean + 0.25};
}

constexpr double kDiameterMm = 7.75;

}  // namespace

// ------------------------------------------------------------------ the tiny study end to end

class ReportTiny : public ::testing::Test {
 protected:
  void SetUp() override {
    run_tiny(dir / "runs.sqlite");
    request.results = dir.path();  // the folder: the report finds runs.sqlite in it
    request.study = source_path("studies/examples/tiny.toml");
    request.out = dir / "report";
  }
  ReportOutcome make(bool plots = true) {
    request.plots = plots;
    std::ostringstream out, log;
    ReportOutcome o = make_report(request, out, log);
    stdout_text = out.str();
    log_text = log.str();
    return o;
  }

  TempDir dir;
  ReportRequest request;
  std::string stdout_text, log_text;
};

TEST_F(ReportTiny, PointsCsvHasOneRowPerPointWithEveryColumn) {
  const ReportOutcome o = make(false);
  EXPECT_EQ(o.n_runs, 12u);
  const Csv csv = read_csv(o.points_csv);
  ASSERT_EQ(csv.rows.size(), 6u) << "2 series x 3 points x 1 model";
  for (const char* name : {"series",
                           "model",
                           "point_label",
                           "bottleneck.gap_mm",
                           "plane.incline_deg",
                           "W_over_d",
                           "D_over_d",
                           "d_mm",
                           "n_runs",
                           "all_passed_fraction",
                           "mean_passed_fraction",
                           "J_paper_mean",
                           "J_paper_t_lo",
                           "J_paper_t_hi",
                           "J_paper_boot_lo",
                           "J_paper_boot_hi",
                           "J_paper_median",
                           "J_paper_clipped_mean",
                           "J_paper_n_dropped",
                           "J_paper_star_mean",
                           "J_flowing_mean",
                           "J_flowing_star_mean",
                           "J_mid_mean",
                           "J_mid_boot_hi",
                           "aval_mean",
                           "aval_lo",
                           "aval_hi",
                           "aval_n",
                           "aval_tail_p",
                           "aval_upper_tail_p",
                           "clog_n",
                           "clog_mean_s",
                           "clog_median_s",
                           "clog_censored_fraction",
                           "regime_continuous",
                           "regime_intermittent",
                           "regime_clogged",
                           "regime_label",
                           "decomp_tau_s",
                           "decomp_j_total",
                           "mean_wall_time_s"})
    csv.column(name);
  EXPECT_EQ(std::count(csv.header.begin(), csv.header.end(), "verdict"), 0) << "no baseline in tiny.toml";
  for (const auto& row : csv.rows) EXPECT_EQ(row.size(), csv.header.size());
  // Study file order, points in order; the axis value as the study wrote it.
  EXPECT_EQ(csv.at(0, "series"), "gap");
  EXPECT_EQ(csv.at(0, "bottleneck.gap_mm"), "19.4");
  EXPECT_EQ(csv.at(2, "bottleneck.gap_mm"), "38.75");
  EXPECT_EQ(csv.at(0, "plane.incline_deg"), "");
  EXPECT_EQ(csv.at(3, "series"), "incline");
  EXPECT_EQ(csv.at(3, "plane.incline_deg"), "6");
  EXPECT_NEAR(std::stod(csv.at(0, "W_over_d")), 19.4 / 7.75, 1e-9);
  EXPECT_NEAR(std::stod(csv.at(0, "d_mm")), 7.75, 1e-9);
  for (std::size_t r = 0; r < 6; ++r) {
    EXPECT_EQ(csv.at(r, "n_runs"), "2") << r;
    const double passed = std::stod(csv.at(r, "mean_passed_fraction")), all = std::stod(csv.at(r, "all_passed_fraction"));
    EXPECT_TRUE(passed >= 0 && passed <= 1) << r;
    if (all == 1) {
      EXPECT_DOUBLE_EQ(passed, 1.0) << r;  // every run emptied: every sphere passed
    }
  }
  // The tables went to stdout too.
  EXPECT_NE(stdout_text.find("series 'incline', model 2d"), std::string::npos) << stdout_text;
}

TEST_F(ReportTiny, MarkdownNamesTheStudyAndTheRegenerateCommand) {
  const ReportOutcome o = make(false);
  ASSERT_TRUE(fs::exists(o.markdown));
  const std::string md = read_text(o.markdown);
  EXPECT_NE(md.find("Study report: tiny"), std::string::npos) << md;
  EXPECT_NE(md.find("60 spheres, a gap sweep and an incline sweep"), std::string::npos) << "the description";
  EXPECT_NE(md.find("- runs: 12 in 6 points"), std::string::npos) << md;
  const std::string command = fmt::format("gapflow report {} --study {} --out {} --no-plots", dir.path().string(),
                                          request.study->string(), request.out->string());
  EXPECT_NE(md.find(command), std::string::npos) << "expected: " << command << "\n" << md;
  EXPECT_NE(md.find("| bottleneck.gap_mm=19.4 | 2.5 |"), std::string::npos) << "the point tables in Markdown:\n" << md;
  EXPECT_NE(md.find(code_version()), std::string::npos);
}

TEST_F(ReportTiny, PlotsAreWrittenWhenMatplotlibIsThere) {
  if (!find_python_with_matplotlib()) GTEST_SKIP() << "no python3 with matplotlib";
  const ReportOutcome o = make(true);
  EXPECT_EQ(o.plot_warning, "") << log_text;
  // tiny's runs clog at most once: no completed avalanche after the first, so
  // no clogging plot (ReportClogging draws one from runs built by hand).
  EXPECT_FALSE(fs::exists(*request.out / "clogging.png"));
  for (const char* png : {"j_star_vs_W_over_d.png", "j_star_vs_plane_incline_deg.png"}) {
    const fs::path p = *request.out / png;
    ASSERT_TRUE(fs::exists(p)) << p;
    EXPECT_EQ(read_text(p).substr(1, 3), "PNG") << p;
    EXPECT_NE(read_text(o.markdown).find(std::string("(") + png + ")"), std::string::npos) << "embedded " << png;
  }
}

TEST(ReportPlots, ScriptDrawsMissingValuesAndAsymmetricBars) {
  const auto python = find_python_with_matplotlib();
  if (!python) GTEST_SKIP() << "no python3 with matplotlib";
  TempDir dir;
  PlotFigure f{"odd.png", "t", "x", "y", {}, {{"ref", "2d", 1.0, 0.8, kNaN}}, true};
  f.lines.push_back({"a", "2d", "errorbar", {1, 2, 3}, {1, kNaN, 2}, {0.5, kNaN, 1.9}, {1.5, 3, kNaN}, {}, {}, ""});
  f.lines.push_back({"b", "3d", "markers", {1}, {2}, {}, {}, {0.5}, {1.5}, ""});
  f.lines.push_back({"b fit", "3d", "curve_fixed", {1, 2}, {2, 3}, {}, {}, {}, {}, "b"});
  // A mean of equal values that rounds a hair above their range (0.1 + 0.2 > 0.3): no negative bar.
  f.lines.push_back({"c", "2d", "errorbar", {1}, {0.1 + 0.2}, {0.3}, {0.3}, {}, {}, ""});
  write_text(dir / "plots.json", plot_spec_json({f}));
  const int rc = run_program({*python, plot_script_path().string(), (dir / "plots.json").string(), dir.path().string()},
                             dir / "log.txt");
  EXPECT_EQ(rc, 0) << read_text(dir / "log.txt");
  EXPECT_TRUE(fs::exists(dir / "odd.png"));
  EXPECT_NE(read_text(dir / "plots.json").find("null"), std::string::npos) << "NaN is written as null";
}

namespace {

// studies/paper_claims.py run on `results`: the claims.md row of `claim` for `model`
// (empty, and a test failure, if the script fails or has no such row). `out` keeps its output.
std::string claims_row(const fs::path& python, const fs::path& results, const fs::path& out, const std::string& claim,
                       const std::string& model) {
  const int rc = run_program(
      {python.string(), (fs::path(GAPFLOW_SOURCE_DIR) / "studies" / "paper_claims.py").string(), results.string()}, out);
  EXPECT_EQ(rc, 0) << read_text(out);
  const std::string md = read_text(out);
  const auto line = md.find("| " + claim + " | " + model + " |");
  EXPECT_NE(line, std::string::npos) << md;
  return line == std::string::npos ? std::string() : md.substr(line, md.find('\n', line) - line);
}

// The verdict of a claims.md row (between its ** **).
std::string verdict_of(const std::string& row) {
  const auto v = row.find("**");
  return v == std::string::npos ? std::string() : row.substr(v + 2, row.find("**", v + 2) - v - 2);
}

}  // namespace

// studies/paper_claims.py: a significant peak is the best of several positions, so the
// claim is held only if the re-test with fresh seeds (cylinder-peak-3d) finds it too.
TEST(PaperClaims, APeakIsHeldOnlyIfItsReTestReproducesIt) {
  const auto python = find_python_with_matplotlib();  // the claims need no matplotlib, but the same python3
  if (!python) GTEST_SKIP() << "no python3 with matplotlib found";
  TempDir dir;
  const std::string header =
      "series,model,n_runs,J_paper_n,J_paper_mean,clog_n,obstruction.distance_mm,D_over_d,d_mm,ratio,ratio_lo,"
      "ratio_hi,verdict,mean_passed_fraction\n";
  fs::create_directories(dir / "flow-vs-distance");
  write_text(dir / "flow-vs-distance" / "points.csv",
             header + "none,3d,6,6,65.6,0,,0,7.75,,,,,1\n"
                      "cylinder,3d,6,6,67.8,0,110,14.19,7.75,1.034,1.025,1.043,significantly above,1\n");
  auto claims_with_retest = [&](const std::string& retest_verdict) {
    fs::create_directories(dir / "cylinder-peak-3d");
    write_text(dir / "cylinder-peak-3d" / "points.csv",
               header + "none,3d,10,10,65.9,0,,0,7.75,,,,,1\n"
                        "cylinder,3d,10,10,65.9,0,,14.19,7.75,1.0,0.98,1.02," + retest_verdict + ",1\n");
    const fs::path out = dir / ("claims_" + retest_verdict + ".md");  // run_program appends to its log
    return claims_row(*python, dir.path(), out, "cylinder: peak above J_0 (waiting room) (IV)", "3d");
  };
  const std::string refuted = claims_with_retest("not distinguishable");
  EXPECT_NE(refuted.find("not reproduced"), std::string::npos) << refuted;
  EXPECT_NE(refuted.find("**not held**"), std::string::npos) << refuted;
  const std::string confirmed = claims_with_retest("significantly above");
  EXPECT_NE(confirmed.find(": reproduced"), std::string::npos) << confirmed;
  EXPECT_NE(confirmed.find("**held**"), std::string::npos) << confirmed;
}

// studies/paper_claims.py: "clogging appears between obstruction and walls" is held only
// where most clogs at the closest position lean on the obstruction (clog-location) and both
// controls at a narrow gap hold: without obstruction the clogs are at the gap, with a far
// cylinder none leans on it (else the locator is not trusted). A report written before
// obstruction contact was measured locates nothing.
TEST(PaperClaims, ClogsBetweenObstructionAndWallsNeedTheirLocationAndWorkingControls) {
  const auto python = find_python_with_matplotlib();
  if (!python) GTEST_SKIP() << "no python3 with matplotlib found";
  TempDir dir;
  fs::create_directories(dir / "flow-vs-distance");
  write_text(dir / "flow-vs-distance" / "points.csv",
             "series,model,n_runs,J_paper_n,J_paper_mean,clog_n,obstruction.distance_mm,D_over_d,d_mm,verdict\n"
             "none,2d,4,4,91,0,,0,7.75,\n"
             "cylinder,2d,4,0,,30,70,9.03,7.75,insufficient data\n");
  int call = 0;
  // Clogs (of 10 located at each point): the plain control's at the gap, the far-cylinder control's
  // and the close cylinder's on the obstruction; "" leaves the column blank; no clog-location study
  // when plain_at_gap is "-".
  auto verdict_with = [&](const std::string& plain_at_gap, const std::string& far_on, const std::string& close_on) {
    fs::remove_all(dir / "clog-location");
    if (plain_at_gap != "-") {
      const std::string zero = close_on.empty() ? "" : "0";  // a report without contact leaves every cell blank
      fs::create_directories(dir / "clog-location");
      write_text(dir / "clog-location" / "points.csv",
                 "series,model,n_runs,clog_n,clog_located_n,clog_at_gap_n,clog_on_obstruction_n,"
                 "obstruction.distance_mm\n"
                 "narrow-gap,2d,4,10,10," + plain_at_gap + "," + zero + ",\n"
                 "narrow-gap-far-cylinder,2d,4,10,10,10," + far_on + ",150\n"
                 "cylinder,2d,4,10,10,0," + (close_on.empty() ? "" : "9") + ",\n"  // no distance: never the closest
                 "cylinder,2d,4,10,10,0," + close_on + ",70\n"
                 "cylinder,2d,4,0,0,0," + zero + ",90\n");
    }
    const fs::path out = dir / fmt::format("claims_{}.md", ++call);
    return verdict_of(claims_row(*python, dir.path(), out, "clogging appears between obstruction and walls (IV, Fig. 2b)", "2d"));
  };
  EXPECT_EQ(verdict_with("-", "", ""), "partly held") << "location not measured";
  EXPECT_EQ(verdict_with("10", "0", "9"), "held") << "9 of 10 on the obstruction, controls hold";
  EXPECT_EQ(verdict_with("10", "0", "2"), "partly held") << "most clogs elsewhere";
  EXPECT_EQ(verdict_with("5", "0", "9"), "not testable") << "the plain control does not clog at the gap";
  EXPECT_EQ(verdict_with("", "0", "9"), "not testable") << "the plain control's sites are unknown";
  EXPECT_EQ(verdict_with("10", "3", "9"), "not testable") << "the far cylinder takes clogs it cannot cause";
  EXPECT_EQ(verdict_with("10", "", ""), "partly held") << "written before obstruction contact was measured";
}

// Where the clogs formed, in points.csv: counts over the located clogs. In a store written
// before clogs were located (here: the location columns emptied), the sites are blank, not 0,
// which would read as "none there".
TEST_F(ReportTiny, ClogSitesAreCountedWhereLocatedAndBlankWhereNot) {
  auto clogged_rows = [](const Csv& csv) {
    std::vector<std::size_t> rows;
    for (std::size_t i = 0; i < csv.rows.size(); ++i)
      if (csv.at(i, "clog_n") != "0") rows.push_back(i);
    return rows;
  };
  const Csv located = read_csv(make(false).points_csv);
  ASSERT_FALSE(clogged_rows(located).empty()) << "tiny.toml's narrow gap clogs";
  for (std::size_t i : clogged_rows(located)) {
    EXPECT_EQ(located.at(i, "clog_located_n"), located.at(i, "clog_n"));
    EXPECT_EQ(located.at(i, "clog_on_obstruction_n"), "0") << "no obstruction in tiny.toml";
    EXPECT_EQ(std::stoi(located.at(i, "clog_at_gap_n")) + std::stoi(located.at(i, "clog_upstream_n")),
              std::stoi(located.at(i, "clog_n")));
  }
  sqlite3* db = nullptr;
  ASSERT_EQ(sqlite3_open((dir / "runs.sqlite").c_str(), &db), SQLITE_OK);
  ASSERT_EQ(sqlite3_exec(db, "UPDATE clogs SET front_m = NULL, on_obstruction = NULL", nullptr, nullptr, nullptr),
            SQLITE_OK);
  sqlite3_close(db);
  const Csv unlocated = read_csv(make(false).points_csv);
  ASSERT_EQ(clogged_rows(unlocated), clogged_rows(located));
  for (std::size_t i : clogged_rows(unlocated)) {
    EXPECT_EQ(unlocated.at(i, "clog_located_n"), "0");
    for (const char* site : {"clog_at_gap_n", "clog_on_obstruction_n", "clog_upstream_n"})
      EXPECT_EQ(unlocated.at(i, site), "") << site;
  }
}

TEST_F(ReportTiny, EveryAnalysisKindRunsOnRealDataWithoutCrashing) {
  const std::string study = read_text(*request.study);
  for (const char* kind : {"flow_vs_gap", "flow_vs_distance", "clogging", "models", "screen_confirm"}) {
    const fs::path file = dir / fmt::format("tiny_{}.toml", kind);
    write_text(file, study + fmt::format("\n[report]\nkind = \"{}\"\nbaseline "
                                         "= \"incline\"\nj = \"flowing\"\n",
                                         kind));
    request.study = file;
    const ReportOutcome o = make(false);
    const std::string md = read_text(o.markdown);
    EXPECT_NE(md.find("## Analysis: "), std::string::npos) << kind;
    EXPECT_NE(md.find("analyses: " + std::string(kind)), std::string::npos) << kind;
    // The incline series (3 points, W/d = 2.71) is a baseline no gap point
    // matches in W/d: no ratios, but the columns are there and nothing breaks.
    const Csv csv = read_csv(o.points_csv);
    EXPECT_EQ(csv.at(0, "baseline"), "") << kind;
    EXPECT_EQ(csv.at(3, "verdict"), "") << "the baseline is not compared to itself";
  }
}

// Pixels inside the board (below the caption, left of the legend) that are a sphere's colour:
// the speed scale (viridis) or the flowing / arch / stuck states. Walls, board, gap line and
// their anti-aliased edges are none of these.
int sphere_pixels(const TopView& layout, const CompiledScenario& sc, const std::function<Rgb(int, int)>& colour_at) {
  std::vector<Rgb> palette;
  for (int i = 0; i <= 256; ++i) palette.push_back(speed_colour(i / 256.0, 1.0));
  for (ParticleState st : {ParticleState::flowing, ParticleState::arch, ParticleState::stuck})
    palette.push_back(state_colour(st));
  auto near = [](Rgb a, Rgb b) { return std::abs(a.r - b.r) <= 2 && std::abs(a.g - b.g) <= 2 && std::abs(a.b - b.b) <= 2; };
  const TopView::Pixel from = layout.to_pixel({-sc.channel_width / 2, sc.plane_length});
  const TopView::Pixel to = layout.to_pixel({sc.channel_width / 2, -0.05});
  int n = 0;
  for (int row = from.row; row < to.row; ++row)
    for (int col = from.col; col < to.col; ++col) {
      const Rgb c = colour_at(col, row);
      n += std::any_of(palette.begin(), palette.end(), [&](Rgb p) { return near(c, p); });
    }
  return n;
}

// Report snapshots: one PNG per point class (tiny has no [report] kind: each series at its
// best point), each a re-run of a stored run that reproduces its crossings up to the picture,
// of the stated size, with spheres on the board, and embedded in report.md; --no-snapshots
// leaves them out and says so.
TEST_F(ReportTiny, SnapshotsAreReRunsOfStoredRunsEmbeddedInTheReport) {
  const ReportOutcome o = make(false);
  ASSERT_EQ(o.snapshots.size(), 2u) << log_text;
  const std::string md = read_text(o.markdown);
  EXPECT_NE(md.find("## Snapshots"), std::string::npos) << md;
  EXPECT_LT(md.find("## Snapshots"), md.find("## Regenerate"));
  // The layout of any tiny point (the plane is the same at every point), and a negative control:
  // a board without spheres has no sphere pixels.
  const CompiledScenario sc = gapflow::testing::compile_file("scenarios/paper/no_obstruction_medium.toml",
                                                             {"particles.count=60"});
  TopView empty(sc, TopViewDef{});
  FrameState nothing;
  nothing.model = "2d";
  empty.draw(nothing);
  EXPECT_EQ(sphere_pixels(empty, sc, [&](int c, int r) { return empty.colour_at({c, r}); }), 0);
  for (const fs::path& png : o.snapshots) {
    EXPECT_NE(md.find("](" + png.filename().string() + ")"), std::string::npos) << png << " embedded";
    cairo_surface_t* image = cairo_image_surface_create_from_png(png.c_str());
    ASSERT_EQ(cairo_surface_status(image), CAIRO_STATUS_SUCCESS) << png << " is not a readable PNG";
    const int w = cairo_image_surface_get_width(image), h = cairo_image_surface_get_height(image);
    EXPECT_EQ(w, empty.width());
    EXPECT_EQ(h, empty.height());
    EXPECT_NE(md.find(fmt::format("{} x {} px", w, h)), std::string::npos) << "the size the report states";
    const unsigned char* data = cairo_image_surface_get_data(image);
    const int stride = cairo_image_surface_get_stride(image);
    const int spheres = sphere_pixels(empty, sc, [&](int c, int r) {
      const unsigned char* px = data + static_cast<std::size_t>(r) * static_cast<std::size_t>(stride) + 4 * c;
      return Rgb{px[2], px[1], px[0]};
    });
    EXPECT_GT(spheres, 300) << png << ": at least ~10 spheres of ~45 px each on the board";
    cairo_surface_destroy(image);
  }
  // Each caption names its stored run by job key and says the re-run reproduced it.
  int keys = 0;
  for (const StoredRun& r : Store(dir / "runs.sqlite").load()) keys += md.find("`" + r.id.key + "`") != std::string::npos;
  EXPECT_EQ(keys, 2);
  std::size_t same = 0;
  for (std::size_t at = 0; (at = md.find("as the stored run: the picture is of that run", at)) != std::string::npos; ++at)
    ++same;
  EXPECT_EQ(same, 2u) << md;
  EXPECT_EQ(o.snapshot_warning, "");

  request.snapshots = false;
  const ReportOutcome none = make(false);
  EXPECT_TRUE(none.snapshots.empty());
  const std::string plain = read_text(none.markdown);
  EXPECT_NE(plain.find("*No snapshots: not requested (--no-snapshots)*"), std::string::npos) << plain;
  EXPECT_EQ(plain.find("](snapshot_"), std::string::npos);
  EXPECT_NE(plain.find("--no-plots --no-snapshots"), std::string::npos) << "the regenerate command";
}

// ------------------------------------------------------------------ flow_vs_distance on known data

TEST(ReportFlowVsDistance, FindsThePeakAndTheSignificantRanges) {
  TempDir dir;
  {
    SyntheticStore s(dir / "runs.sqlite");
    s.add_point("none", "2d", 0, std::nullopt, around(10.0));
    // J/J_0 by distance: 1.0, 1.2, 1.5, 1.2, 1.0, 0.8, 1.0, 1.2, then a point where nothing passed.
    const std::vector<double> gain{1.0, 1.2, 1.5, 1.2, 1.0, 0.8, 1.0, 1.2};
    for (std::size_t i = 0; i < gain.size(); ++i)
      s.add_point("cylinder", "2d", static_cast<int>(i), 10.0 * (i + 1), around(10.0 * gain[i]));
    s.add_point("cylinder", "2d", 8, 90.0, {1, 1, 1}, /*clogged=*/true);
  }
  const fs::path study = dir / "study.toml";
  write_text(study,
             "[study]\nname = \"synthetic\"\n[[series]]\nlabel = "
             "\"none\"\nscenario = \"x.toml\"\n"
             "[[series]]\nlabel = \"cylinder\"\nscenario = \"x.toml\"\n"
             "[report]\nkind = \"flow_vs_distance\"\nbaseline = \"none\"\n");
  const StudyInfo info = read_study_info(study);
  ASSERT_EQ(info.report.kinds, std::vector<ReportKind>{ReportKind::flow_vs_distance});
  const ReportData data = collect_report_data(Store(dir / "runs.sqlite").load(), info);
  const FlowVsDistanceAnalysis a = analyze_flow_vs_distance(data, info.report);
  ASSERT_TRUE(a.baseline_found);
  ASSERT_EQ(a.results.size(), 1u);
  const DistanceResult& r = a.results[0];
  EXPECT_EQ(r.n_points, 9u);
  EXPECT_EQ(r.n_compared, 8u) << "the clogged point has no J_paper";
  EXPECT_NEAR(r.peak_d_over_d, 30.0 / kDiameterMm, 1e-9);
  EXPECT_NEAR(r.peak.mean, 15.0, 1e-9);
  EXPECT_NEAR(r.baseline.mean, 10.0, 1e-9);
  ASSERT_TRUE(r.peak_gain);
  EXPECT_NEAR(r.peak_gain->ratio, 1.5, 1e-9);
  EXPECT_TRUE(r.peak_gain->ratio_ci.contains(1.5));
  EXPECT_GT(r.peak_gain->ratio_ci.lo, 1.4);
  EXPECT_EQ(r.peak_gain->verdict, Verdict::significantly_above);
  ASSERT_EQ(r.above.size(), 2u) << "two separate ranges";
  EXPECT_NEAR(r.above[0].from, 20.0 / kDiameterMm, 1e-9);
  EXPECT_NEAR(r.above[0].to, 40.0 / kDiameterMm, 1e-9);
  EXPECT_EQ(r.above[0].n_points, 3u);
  EXPECT_NEAR(r.above[1].from, 80.0 / kDiameterMm, 1e-9);
  EXPECT_EQ(r.above[1].n_points, 1u);
  ASSERT_EQ(r.below.size(), 1u);
  EXPECT_NEAR(r.below[0].from, 60.0 / kDiameterMm, 1e-9);
  EXPECT_EQ(r.below[0].n_points, 1u);

  // The clogged point has no J to draw: the discharge figure shows how far its runs got (40 of 100).
  const auto figures = generic_figures(data, JKind::paper);
  const auto discharged = std::find_if(figures.begin(), figures.end(),
                                       [](const PlotFigure& f) { return f.file == "discharged_vs_D_over_d.png"; });
  ASSERT_NE(discharged, figures.end());
  ASSERT_EQ(discharged->lines.size(), 1u) << "the baseline has no distance axis";
  const PlotLine& line = discharged->lines[0];
  ASSERT_EQ(line.y.size(), 9u);
  EXPECT_DOUBLE_EQ(line.y[0], 1.0);
  EXPECT_NEAR(line.x[8], 90.0 / kDiameterMm, 1e-9);
  EXPECT_DOUBLE_EQ(line.y[8], 0.4);
  EXPECT_DOUBLE_EQ(line.ylo[8], 0.4);
  EXPECT_DOUBLE_EQ(line.yhi[8], 0.4);

  // The whole report on the same store: ratios in points.csv, n/a for the clogged point, the section.
  std::ostringstream out, log;
  ReportRequest req;
  req.results = dir / "runs.sqlite";
  req.study = study;
  req.plots = false;
  const ReportOutcome o = make_report(req, out, log);
  const Csv csv = read_csv(o.points_csv);
  ASSERT_EQ(csv.rows.size(), 10u);
  EXPECT_EQ(csv.at(0, "series"), "none") << "study file order";
  EXPECT_EQ(csv.at(3, "verdict"), "significantly above");
  EXPECT_NEAR(std::stod(csv.at(3, "ratio")), 1.5, 1e-9);
  EXPECT_EQ(csv.at(6, "verdict"), "significantly below");
  EXPECT_EQ(csv.at(9, "J_paper_mean"), "") << "undefined, not 0";
  EXPECT_EQ(csv.at(9, "verdict"), "insufficient data");
  const std::string md = read_text(o.markdown);
  EXPECT_NE(md.find("## Analysis: Flow rate against the obstruction distance"), std::string::npos) << md;
  EXPECT_NE(md.find("J_paper is significantly above J_0 at D/d = 2.58-5.16, "
                    "10.3, and significantly below J_0 at D/d = 7.74"),
            std::string::npos)
      << md;
  EXPECT_NE(out.str().find("n/a"), std::string::npos) << "the clogged point prints n/a";

  // Snapshot classes of a distance study: the reference and the cylinder at its peak (30 mm),
  // the replicate nearest the median J; the study's scenario file does not exist, so the
  // report says why it has no pictures instead of failing.
  const std::vector<StoredRun> runs = Store(dir / "runs.sqlite").load();
  const std::vector<SnapshotPick> picks = choose_snapshots(data, runs);
  ASSERT_EQ(picks.size(), 2u);
  EXPECT_EQ(picks[0].cls, "J_0 reference");
  EXPECT_EQ(picks[0].point->series, "none");
  EXPECT_EQ(picks[1].cls, "cylinder at its best position");
  EXPECT_EQ(picks[1].point->point_label, "obstruction.distance_mm=30");
  EXPECT_TRUE(picks[1].run->id.replicate == 2 || picks[1].run->id.replicate == 3) << picks[1].run_why;
  EXPECT_FALSE(picks[1].at_clog);
  EXPECT_NEAR(picks[1].t_s, picks[1].run->record.sim_time_s / 2, 1e-12) << "no crossings stored: half-way";
  EXPECT_NE(md.find("*No snapshots: the study's jobs could not be rebuilt"), std::string::npos) << md;

  // Without --study: a bare report and a warning, until the store records the study file.
  req.study.reset();
  std::ostringstream out2, log2;
  const ReportOutcome bare = make_report(req, out2, log2);
  EXPECT_EQ(read_text(bare.markdown).find("## Analysis:"), std::string::npos);
  EXPECT_NE(log2.str().find("give --study"), std::string::npos) << log2.str();
  Store(dir / "runs.sqlite").record_study_file("synthetic", study.string(), read_text(study));
  std::ostringstream out3, log3;
  const ReportOutcome recorded = make_report(req, out3, log3);
  const std::string recorded_md = read_text(recorded.markdown);
  EXPECT_NE(recorded_md.find("## Analysis: Flow rate against the obstruction distance"), std::string::npos);
  EXPECT_NE(recorded_md.find(", file `" + study.string() + "` (the copy recorded in the store at "), std::string::npos)
      << "the header names the recorded file, not 'no study file given'";
  EXPECT_NE(log3.str().find("using the study file recorded in the store"), std::string::npos) << log3.str();
}

// ------------------------------------------------------------------ models

TEST(ReportModels, IdenticalRecordsGiveRatioOneAndPerfectAgreement) {
  TempDir dir;
  {
    SyntheticStore s(dir / "runs.sqlite");
    for (int p = 0; p < 4; ++p)
      for (const char* model : {"2d", "3d"}) s.add_point("cyl", model, p, 10.0 * (p + 1), around(8.0 + 3 * p * p));
  }
  StudyInfo info;
  info.report.kinds = {ReportKind::models};
  const ReportData data = collect_report_data(Store(dir / "runs.sqlite").load(), info);
  const ModelsAnalysis a = analyze_models(data, info.report);
  ASSERT_EQ(a.pairs.size(), 4u);
  for (const ModelPair& m : a.pairs) {
    EXPECT_DOUBLE_EQ(m.ratio.ratio, 1.0) << m.point_label;
    EXPECT_TRUE(m.ratio.ratio_ci.contains(1.0)) << m.point_label;
    EXPECT_EQ(m.ratio.verdict, Verdict::not_distinguishable);
    EXPECT_DOUBLE_EQ(m.j2d_star.mean, m.j3d_star.mean);
  }
  EXPECT_EQ(a.n_both, 4u);
  EXPECT_DOUBLE_EQ(a.mean_ratio, 1.0);
  EXPECT_NEAR(a.pearson, 1.0, 1e-12);
  EXPECT_NEAR(a.spearman, 1.0, 1e-12);
  const ExperimentSection s = models_section(data, info.report);
  ASSERT_EQ(s.figures.size(), 1u);
  EXPECT_TRUE(s.figures[0].identity_line);
  ASSERT_EQ(s.figures[0].lines.size(), 1u);
  EXPECT_EQ(s.figures[0].lines[0].x, s.figures[0].lines[0].y);
}

// --compare 3d=STORE: a 2D-only study's report takes the 3D runs of another study's store,
// point by point; refused when the own store has 3D runs or the other none.
TEST(ReportModels, CompareBringsTheOtherModelsRunsFromAnotherStore) {
  TempDir dir;
  {
    SyntheticStore own(dir / "own.sqlite"), other(dir / "other.sqlite", "other-study");
    for (int p = 0; p < 3; ++p) {
      own.add_point("cyl", "2d", p, 10.0 * (p + 1), around(8.0 + 3 * p));
      other.add_point("cyl", "2d", p, 10.0 * (p + 1), around(99.0));  // not taken: the wrong model
      other.add_point("cyl", "3d", p, 10.0 * (p + 1), around(4.0 + 3 * p));
    }
  }
  ReportRequest r;
  r.results = dir / "own.sqlite";
  r.out = dir / "report";
  r.plots = false, r.snapshots = false;
  r.compare = ReportRequest::Compare{"3d", dir / "other.sqlite"};
  r.j = JKind::mid;  // --j: the analyses' flow rate instead of the study's
  std::ostringstream out, log;
  make_report(r, out, log);
  const Csv csv = read_csv(dir / "report" / "points.csv");
  int rows_3d = 0;
  for (std::size_t i = 0; i < csv.rows.size(); ++i)
    if (csv.at(i, "model") == "3d") {
      ++rows_3d;
      EXPECT_NEAR(std::stod(csv.at(i, "J_paper_mean")), 4.0 + 3 * std::stoi(csv.at(i, "point")), 1e-9);
    } else {
      EXPECT_NEAR(std::stod(csv.at(i, "J_paper_mean")), 8.0 + 3 * std::stoi(csv.at(i, "point")), 1e-9);
    }
  EXPECT_EQ(rows_3d, 3);
  const std::string md = read_text(dir / "report" / "report.md");
  EXPECT_NE(md.find("The 3d runs (18) are those of study \"other-study\""), std::string::npos) << md.substr(0, 600);
  EXPECT_NE(md.find("--compare 3d="), std::string::npos);
  EXPECT_NE(md.find(" --j mid"), std::string::npos);
  EXPECT_NE(md.find("# Study report: synthetic"), std::string::npos) << "relabelled as the own study's";
  EXPECT_NE(md.find("fix the same settings was not checked"), std::string::npos) << "no study file recorded";

  const auto error_of = [&](ReportRequest q) -> std::string {
    try {
      make_report(q, out, log);
    } catch (const std::invalid_argument& e) {
      return e.what();
    }
    return "";
  };
  ReportRequest q = r;
  q.results = dir / "other.sqlite";  // it has 3D runs of its own
  EXPECT_NE(error_of(q).find("already has 3d runs"), std::string::npos) << error_of(q);
  q = r;
  q.compare = ReportRequest::Compare{"2d", dir / "other.sqlite"};  // own 2D runs: two sources
  EXPECT_NE(error_of(q).find("already has 2d runs"), std::string::npos) << error_of(q);
  {
    SyntheticStore third(dir / "other.sqlite", "third-study", 1000);  // a second study's 3D runs beside other's
    third.add_point("cyl", "3d", 0, 10.0, around(5.0));
  }
  const std::string several = error_of(r);
  EXPECT_NE(several.find("of 2 studies (other-study, third-study)"), std::string::npos) << several;
  {
    SyntheticStore none(dir / "none.sqlite", "none-study");
    none.add_point("cyl", "2d", 0, 10.0, around(5.0));
  }
  q = r;
  q.compare = ReportRequest::Compare{"3d", dir / "none.sqlite"};
  EXPECT_NE(error_of(q).find("holds 3d runs of 0 studies"), std::string::npos) << error_of(q);
}

// --compare: the two study files' settings for their common series, [per_model] sets aside.
TEST(ReportModels, CompareNamesTheSettingsTheTwoStudyFilesFixDifferently) {
  const std::string own = R"([study]
name = "own"
set = ["run.time_limit_s=40", "run.stop_after_no_flow_s=20"]
[per_model.2d]
set = ["model.box2d.rolling_contact=1"]
[[series]]
label = "none"
scenario = "../../scenarios/paper/cylinder.toml"
set = ["obstruction.shape=none"]
[[series]]
label = "cyl"
scenario = "../../scenarios/paper/cylinder.toml"
)";
  std::string other = own;
  EXPECT_TRUE(study_setting_differences(own, "own.toml", other, "other.toml").empty());
  other.replace(other.find("rolling_contact=1"), 17, "rolling_contact=0");  // one model's: not compared
  EXPECT_TRUE(study_setting_differences(own, "own.toml", other, "other.toml").empty());
  other.replace(other.find("time_limit_s=40"), 15, "time_limit_s=60");
  other.replace(other.find("scenarios/paper/cylinder.toml\"\nset"), 29, "scenarios/paper/v_obstruction.toml");
  other += "set = [\"obstruction.corner_radius_mm=1\"]\n[[series]]\nlabel = \"only-there\"\nscenario = \"x.toml\"\n";
  const std::vector<std::string> d = study_setting_differences(own, "own.toml", other, "other.toml");
  ASSERT_EQ(d.size(), 3u) << fmt::format("{}", fmt::join(d, " | "));
  EXPECT_EQ(d[0], "[study] set run.time_limit_s: 40 here, 60 there");
  EXPECT_EQ(d[1], "series 'cyl' set obstruction.corner_radius_mm: unset here, 1 there");
  EXPECT_EQ(d[2], "series 'none' scenario: cylinder.toml here, v_obstruction.toml there");
}

// ------------------------------------------------------------------ clogging

// Runs whose avalanches after the first all have size s = 2^k - 1 at W/d = sqrt(k): then
// ln(<s>+1) = ln 2 (W/d)^2 exactly (the censoring-aware mean of equal completed sizes is s).
namespace {

// Clogged runs at (W/d)^2 = 1..gaps whose completed avalanches all have size 2^k - 1.
std::vector<StoredRun> clogging_runs(int gaps) {
  std::vector<StoredRun> runs;
  for (int k = 1; k <= gaps; ++k)
    for (int rep = 0; rep < 2; ++rep) {
      StoredRun r;
      r.id.key = fmt::format("{:016x}", 100 * k + rep);
      r.id.study = "clog", r.id.series = "small", r.id.model = "2d", r.id.point = k - 1, r.id.replicate = rep;
      r.id.point_label = fmt::format("bottleneck.gap_mm={}", k);
      r.id.axes_json = fmt::format("{{\"bottleneck.gap_mm\":{}}}", k);
      r.record = synthetic_run("2d", 10.0, 0.0, rep, /*clogged=*/true);
      r.record.gap_m = std::sqrt(static_cast<double>(k)) * r.record.diameter_m;
      const int s = (1 << k) - 1;
      r.record.avalanches.push_back({7, 0.0, 1.0, true, false});  // the first: excluded
      for (int i = 0; i < 10; ++i) r.record.avalanches.push_back({s, 2.0 + i, 2.5 + i, false, false});
      r.record.clogs.push_back({1.0, 2.0, false, std::nullopt});  // one completed clog of 2 s
      r.record.clogs.push_back({12.5, 30.0, true, std::nullopt});
      runs.push_back(std::move(r));
    }
  return runs;
}

}  // namespace

TEST(ReportClogging, FitsLnMeanSizeAgainstGapSquared) {
  const std::vector<StoredRun> runs = clogging_runs(4);
  StudyInfo info;
  info.report.kinds = {ReportKind::clogging};
  const ReportData data = collect_report_data(runs, info);
  const CloggingAnalysis a = analyze_clogging(data);
  ASSERT_EQ(a.series.size(), 1u);
  const ClogSeries& cs = a.series[0];
  ASSERT_EQ(cs.points.size(), 4u);
  EXPECT_NEAR(cs.points[2].w2, 3.0, 1e-9);
  EXPECT_NEAR(cs.points[2].ln_s1, 3 * std::log(2.0), 1e-9);
  EXPECT_LT(cs.points[2].ln_lo, cs.points[2].ln_s1);
  ASSERT_TRUE(cs.fit.ok);
  EXPECT_EQ(cs.fit.weighting, "interval widths");
  EXPECT_NEAR(cs.fit.slope, std::log(2.0), 1e-9);
  EXPECT_NEAR(cs.fit.intercept, 0.0, 1e-9);
  // The generic clogging figure exists (avalanche data) and the section draws the fit onto it.
  const auto figures = generic_figures(data, JKind::paper);
  EXPECT_TRUE(
      std::any_of(figures.begin(), figures.end(), [](const PlotFigure& f) { return f.file == "clogging.png"; }));
  const ExperimentSection sec = clogging_section(data, info.report);
  ASSERT_EQ(sec.overlays.count("clogging.png"), 1u);
  EXPECT_EQ(sec.overlays.at("clogging.png").at(0).x.size(), 2u);
  EXPECT_NE(render_markdown(sec.tables.at(1)).find("| small | 2D | 0.6931"), std::string::npos)
      << render_markdown(sec.tables.at(1));
  // The decomposition table: at (W/d)^2 = 2 each run has the first avalanche (7 spheres in
  // 1 s), ten of 3 in 0.5 s and one completed clog of 2 s: tau = (1 + 10 x 0.5) / (6 + 10 x 2) s,
  // <s> = 37/11, T_flow = (6 + 11 tau)/11, T_clog = 2 - tau, so <s>/(T_flow + T_clog) =
  // 37/28 and J_total = 37 / (6 + 11 tau + 2 - tau).
  const TextTable& decomposition = sec.tables.at(2);
  ASSERT_EQ(decomposition.rows.size(), 4u);
  const std::vector<std::string>& row = decomposition.rows[1];
  const double tau = 6.0 / 26.0;
  EXPECT_EQ(row[4], "2") << "completed clogs, pooled over the two runs";
  EXPECT_EQ(row[5], fmt_num(37.0 / 11.0, 4));
  EXPECT_EQ(row[6], fmt_num(tau, 4));
  EXPECT_EQ(row[7], fmt_num((6.0 + 11.0 * tau) / 11.0, 4));
  EXPECT_EQ(row[8], fmt_num(2.0 - tau, 4));
  EXPECT_EQ(row[9], fmt_num(37.0 / 28.0, 4));
  EXPECT_EQ(row[10], fmt_num(37.0 / (8.0 + 10.0 * tau), 4));
  EXPECT_EQ(row[12], fmt_num(1.0 / tau, 4)) << "1/tau";
  // No J_paper anywhere (every run clogged): the tables say n/a and the J* figure has no line.
  EXPECT_NE(render_text(point_tables(data, JKind::paper).at(0)).find("n/a"), std::string::npos);
}

// The size-distribution figure: twenty sizes, 1 x 10, 2 x 6, 3 x 4 (mean 1.7, q = 1 - 1/1.7)
// give ln P(S >= s) = 0, ln(10/20), ln(4/20) at x = 0, -ln q, -2 ln q; a point whose
// sizes are all 1 (no geometric fit) draws nothing.
TEST(ReportClogging, SizeDistributionIsScaledSoThatTheGeometricLawIsMinusX) {
  std::vector<StoredRun> runs = clogging_runs(2);
  for (StoredRun& r : runs) {
    if (r.id.point != 1) continue;
    r.record.avalanches.resize(1);  // keep the first (excluded)
    for (int i = 0; i < 10; ++i)
      r.record.avalanches.push_back({i % 2 == 0 ? 1 : (i % 4 == 1 ? 2 : 3), 2.0 + i, 2.5 + i, false, false});
  }
  // Per run: i = 0..9 gives sizes 1,2,1,3,1,2,1,3,1,2 -> 5 ones, 3 twos, 2 threes; two runs.
  StudyInfo info;
  info.report.kinds = {ReportKind::clogging};
  const ReportData data = collect_report_data(runs, info);
  const ExperimentSection sec = clogging_section(data, info.report);
  ASSERT_EQ(sec.figures.size(), 1u);
  const PlotFigure& f = sec.figures[0];
  EXPECT_EQ(f.file, "avalanche_sizes.png");
  ASSERT_EQ(f.lines.size(), 2u) << "point 0 (all sizes 1) draws nothing; the law's line";
  const PlotLine& l = f.lines[0];
  const double mean = (10 * 1 + 6 * 2 + 4 * 3) / 20.0, rate = -std::log(1.0 - 1.0 / mean);
  ASSERT_EQ(l.x.size(), 3u);
  EXPECT_NEAR(l.x[1], rate, 1e-12);
  EXPECT_NEAR(l.x[2], 2 * rate, 1e-12);
  EXPECT_NEAR(l.y[0], 0.0, 1e-12);
  EXPECT_NEAR(l.y[1], std::log(10.0 / 20.0), 1e-12);
  EXPECT_NEAR(l.y[2], std::log(4.0 / 20.0), 1e-12);
  EXPECT_EQ(f.lines[1].label, "geometric law");
  EXPECT_NEAR(f.lines[1].y.back(), -f.lines[1].x.back(), 1e-12);
}

// The screen -> confirm section holds the 2D/3D comparison: asking for both gives it once.
TEST(ReportModels, ScreenConfirmAndModelsGiveOneComparison) {
  StudyInfo info;
  info.report.kinds = {ReportKind::screen_confirm, ReportKind::models};
  const ReportData data = collect_report_data(clogging_runs(2), info);
  const std::vector<ExperimentSection> sections = experiment_sections(data, info.report);
  ASSERT_EQ(sections.size(), 1u);
  EXPECT_EQ(sections[0].title, "Screen (2D) and confirmation (3D)");
  info.report.kinds = {ReportKind::models};
  EXPECT_EQ(experiment_sections(data, info.report).size(), 1u);
}

// Two gaps: the line goes through both points exactly, with no interval; it is not drawn.
TEST(ReportClogging, ALineThroughTwoPointsIsNotDrawn) {
  StudyInfo info;
  info.report.kinds = {ReportKind::clogging};
  const ReportData data = collect_report_data(clogging_runs(2), info);
  const ExperimentSection sec = clogging_section(data, info.report);
  ASSERT_EQ(sec.overlays.count("clogging.png"), 1u);
  EXPECT_TRUE(sec.overlays.at("clogging.png").at(0).x.empty());
  EXPECT_NE(render_markdown(sec.tables.at(1)).find("not drawn: 2 points"), std::string::npos)
      << render_markdown(sec.tables.at(1));
}

// ------------------------------------------------------------------ pieces

TEST(ReportPieces, LineFitRecoversAnExactLineAndRefusesOneX) {
  const LineFit f = fit_line({1, 2, 3, 4}, {5, 8, 11, 14}, {0.1, 0.1, 0.2, 0.1});
  ASSERT_TRUE(f.ok);
  EXPECT_NEAR(f.slope, 3.0, 1e-12);
  EXPECT_NEAR(f.intercept, 2.0, 1e-12);
  EXPECT_TRUE(f.slope_ci.contains(3.0));
  EXPECT_EQ(f.weighting, "interval widths");
  // Noisy: the interval widens with the scatter.
  const LineFit g = fit_line({1, 2, 3, 4, 5}, {1.1, 1.9, 3.2, 3.8, 5.1});
  EXPECT_EQ(g.weighting, "unweighted");
  EXPECT_TRUE(g.slope_ci.contains(g.slope));
  EXPECT_GT(g.slope_ci.width(), 0.05);
  EXPECT_FALSE(fit_line({2, 2, 2}, {1, 2, 3}).ok);
  EXPECT_FALSE(fit_line({}, {}).ok);
}

TEST(ReportPieces, SpearmanUsesRanksWithTies) {
  EXPECT_NEAR(spearman_correlation({1, 2, 3, 4}, {10, 20, 30, 1000}), 1.0, 1e-12);
  EXPECT_NEAR(spearman_correlation({1, 2, 3, 4}, {4, 3, 2, 1}), -1.0, 1e-12);
  EXPECT_NEAR(spearman_correlation({1, 2, 2, 3}, {1, 2, 2, 3}), 1.0, 1e-12);
  EXPECT_TRUE(std::isnan(spearman_correlation({1}, {1})));
}

TEST(ReportPieces, AxesJsonKeepsOrderTextAndNumbers) {
  const auto a = parse_axes_json(R"({"obstruction.distance_mm":90.0,"obstruction.shape":"cylinder","x":true})");
  ASSERT_EQ(a.size(), 3u);
  EXPECT_EQ(a[0].key, "obstruction.distance_mm");
  EXPECT_EQ(a[0].text, "90.0");
  EXPECT_EQ(a[0].number, 90.0);
  EXPECT_EQ(a[1].text, "cylinder");
  EXPECT_TRUE(std::isnan(a[1].number));
  EXPECT_EQ(a[2].text, "true");
  EXPECT_TRUE(parse_axes_json("{}").empty());
  EXPECT_THROW(parse_axes_json("{\"a\":}"), std::runtime_error);
}

TEST(ReportPieces, ReportTableIsReadStrictlyWithItsLine) {
  const StudyInfo ok = parse_study_info(
      "[study]\nname = \"s\"\nreplicates = 3\nmodels = [\"2d\", "
      "\"3d\"]\n[report]\nkind = \"clogging\"\nj = \"mid\"\n",
      "s.toml");
  EXPECT_EQ(ok.name, "s");
  EXPECT_EQ(ok.replicates, 3);
  EXPECT_EQ(ok.models, (std::vector<std::string>{"2d", "3d"}));
  EXPECT_EQ(ok.report.kinds, std::vector<ReportKind>{ReportKind::clogging});
  const StudyInfo two = parse_study_info("[report]\nkind = [\"models\", \"flow_vs_gap\"]\nfit_w_min = 2\n", "s.toml");
  EXPECT_EQ(two.report.kinds, (std::vector<ReportKind>{ReportKind::models, ReportKind::flow_vs_gap}));
  EXPECT_EQ(two.report.fit_w_min, 2.0);
  EXPECT_EQ(ok.report.j, JKind::mid);
  try {
    parse_study_info(
        "[study]\nname = \"s\"\n[report]\nkind = "
        "\"clogging\"\nbasline = \"none\"\n",
        "s.toml");
    ADD_FAILURE() << "no error for a misspelt key";
  } catch (const ScenarioError& e) {
    EXPECT_EQ(e.key(), "report.basline");
    EXPECT_EQ(e.where().line, 5);
  }
  try {
    parse_study_info("[report]\nkind = \"flow_vs_gaps\"\n", "s.toml");
    ADD_FAILURE() << "no error for a bad kind";
  } catch (const ScenarioError& e) {
    EXPECT_EQ(e.key(), "report.kind");
    EXPECT_NE(std::string(e.what()).find("flow_vs_gap"), std::string::npos) << e.what();
  }
}

TEST(ReportPieces, MissingStoreIsBadInputAndNothingIsCreated) {
  TempDir dir;
  ReportRequest r;
  r.results = dir / "nothing" / "runs.sqlite";
  std::ostringstream out, log;
  EXPECT_THROW(make_report(r, out, log), std::invalid_argument);
  EXPECT_FALSE(fs::exists(dir / "nothing"));
}

TEST(ReportPieces, ShippedStudiesReportTablesReadTheSameAsTheStudyLoader) {
  int n = 0;
  for (const auto& entry : fs::directory_iterator(source_path("studies/paper"))) {
    if (entry.path().extension() != ".toml") continue;
    ++n;
    const StudyDef def = load_study(entry.path());
    const StudyInfo info = read_study_info(entry.path());
    EXPECT_EQ(info.name, def.name) << entry.path();
    EXPECT_EQ(info.report.baseline, def.report.baseline) << entry.path();
    EXPECT_EQ(to_string(info.report.j), "J_" + def.report.j) << entry.path();
    std::vector<std::string> kinds;
    for (ReportKind k : info.report.kinds) kinds.push_back(to_string(k));
    EXPECT_EQ(kinds, def.report.kinds) << entry.path();
  }
  EXPECT_GT(n, 0) << "no shipped study files";
}

// One table names each flow rate: in study files and --j ("mid"), and in tables ("J_mid").
TEST(ReportOptions, FlowRateNamesRoundTrip) {
  ASSERT_EQ(jkind_option_names(), (std::vector<std::string>{"paper", "flowing", "mid"}));
  for (JKind k : {JKind::paper, JKind::flowing, JKind::mid}) {
    EXPECT_EQ(jkind_from_option(option_name(k)), k);
    EXPECT_EQ(std::string(to_string(k)), std::string("J_") + option_name(k));
  }
  EXPECT_FALSE(jkind_from_option("J_mid").has_value());
  EXPECT_FALSE(jkind_from_option("").has_value());
}

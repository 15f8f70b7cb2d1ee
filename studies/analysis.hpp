// Per-point aggregation of run records: one "point" is a set of replicate runs of one
// scenario (one gap, one obstruction position). Engine-independent and deterministic.
//
// What is reported, and why several views side by side:
//   * J (paper / flowing / 10-90 %): Student-t and bootstrap intervals, median, and the
//     paper's 2-sigma-drop mean (Murray & Alonso-Marroquin 2016, sec. IV). Long clogs give J
//     a heavy lower tail; the views disagree exactly when that matters, so none is chosen.
//   * avalanche sizes: the first avalanche (from the initial packing) is excluded; the mean
//     is the censoring-aware exponential/geometric MLE with its chi-square interval, plus a
//     goodness-of-fit check (2D avalanche sizes are expected to be exponential:
//     Thomas & Durian 2015; reference/physics-and-engines.md).
//   * clog durations: mean, median, fraction censored, Hill tail exponent.
//   * the decomposition J = <s> / (<T_flow> + <T_clog>) (definitions at FlowDecomposition).
//   * regime fractions and a label.
#pragma once

#include "common/run_record.hpp"
#include "common/statistics.hpp"

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace gapflow {

struct AvalancheStatistics {
  std::size_t n_all = 0;            // avalanches in all runs
  std::size_t n_first_excluded = 0; // flagged first, not used below
  CensoredMean size;                // censoring-aware mean size (particles) and its chi-square interval
  TailCheck tail;                   // geometric fit of the UNCENSORED sizes (KS + parametric bootstrap)
  TailCheck upper_tail;             // the same on the sizes >= ceil(<s>) only: the exponential-TAIL check
  std::vector<int> sizes;           // uncensored sizes used by `tail`
};

struct ClogStatistics {
  std::size_t n = 0;
  std::size_t n_censored = 0;
  double fraction_censored = kNaN;
  double mean_uncensored_s = kNaN;  // s, completed clogs only
  double median_uncensored_s = kNaN;
  double mean_all_s = kNaN;         // s, censored ones at their observed (lower-bound) length
  double max_s = kNaN;
  // Power-law tail of the COMPLETED clog durations, top 20 % (statistics.hpp for the caveat).
  // Censored clogs are left out: a permanent clog is stopped at run.stop_after_no_flow_s, a
  // fixed number that would distort the tail.
  HillEstimate tail;
  bool heavy_tail = false;          // tail.alpha < 2: infinite variance, J's mean over runs converges slowly
  // Where the clogs formed (clog_site in common/measurement.hpp), over the clogs whose
  // front was measured (records stored before have none): n_located = the three sites.
  std::size_t n_located = 0;
  std::size_t n_at_gap = 0;          // an arch across the gap: mouth occupied, obstruction not touched
  std::size_t n_on_obstruction = 0;  // the arch leans on the obstruction: between obstruction and walls
  std::size_t n_upstream = 0;        // the mouth ran empty and the arch does not lean on the obstruction
  // Located by their front distance alone (records made before Clog::on_obstruction was
  // measured): counted in n_at_gap or n_upstream, and so n_on_obstruction is not known.
  std::size_t n_contact_not_measured = 0;
  double median_front_d = kNaN;      // median distance of the front from the gap centre, in nominal d
};

// J = <s> / (<T_flow> + <T_clog>).
//
// A clog in the run record lasts from the last crossing of an avalanche to the first crossing
// of the next, so avalanche durations (first to last crossing) and clog durations tile the
// time from the first to the last crossing. Each avalanche of s crossings spans s - 1
// inter-crossing intervals; we give it one more, the interval "owed" to its last particle:
//   tau      = sum over avalanches (t_end - t_start) / sum (s - 1)     (pooled over all runs;
//              the mean time between crossings while flowing; 1/tau = flowing rate)
//   T_flow   = (t_end - t_start) + tau                 per avalanche
//   T_clog   = duration - tau                          per completed clog (time really blocked)
// so T_flow + T_clog keeps the cycle length. All avalanches are used (the first included: J_paper
// includes it too); only completed clogs (censored ones end with the run, not the clog).
// Three rates:
//   j_flow   = <s> / <T_flow>                  = 1/tau exactly: the rate while flowing
//   j_cycle  = <s> / (<T_flow> + <T_clog>)     the paper's form: steady state, one clog per avalanche
//   j_total  = sum s / (sum T_flow + sum T_clog) = <s> / (<T_flow> + (n_clogs/n_aval) <T_clog>)
// For periodic crossings (period tau) starting one tau after release, j_total = N / t_last =
// J_paper exactly, and j_flow = J_flowing for a run without clogs (tests/test_analysis.cpp).
struct FlowDecomposition {
  bool valid = false;               // needs at least one avalanche with s >= 2
  std::size_t n_avalanches = 0;
  std::size_t n_clogs = 0;          // completed clogs used
  double tau_s = kNaN;
  double mean_size = kNaN;          // <s>, particles
  double mean_t_flow_s = kNaN;
  double mean_t_clog_s = kNaN;      // NaN without completed clogs
  double j_flow = kNaN;             // particles/s
  double j_cycle = kNaN;            // particles/s (= j_flow without clogs)
  double j_total = kNaN;            // particles/s
};

// Fractions of runs per regime (run_record.hpp). Label: the regime of a strict majority
// (> `majority` of the runs), otherwise "mixed".
struct RegimeFractions {
  std::size_t n = 0;
  double continuous = 0, intermittent = 0, clogged = 0;
  std::string label = "none";
};

using ReplicateKey = std::pair<std::uint64_t, int>;  // (run.seed, run.replicate)

struct PointStatistics {
  std::size_t n_runs = 0;
  std::string scenario_name;        // of the first run
  double w_over_d = kNaN, distance_over_d = kNaN;  // W/d and D/d (nominal d) of the first run
  double j_star_factor = kNaN;      // sqrt(d/g), g = 9.81 m/s^2: multiply a J (1/s) to get J*

  double all_passed_fraction = kNaN;   // share of runs in which every particle passed (NaN: all runs re-injected)
  double mean_passed_fraction = kNaN;  // mean of passed/N over runs without re-injection (NaN if none)
  double min_passed_fraction = kNaN, max_passed_fraction = kNaN;  // their range over those runs
  long escaped_total = 0;              // must be 0
  int max_conservation_error = 0;      // must be 0

  // Per-run flow rates (particles/s; runs where the rate is undefined are left out) and their statistics.
  std::vector<double> j_paper_values, j_flowing_values, j_mid_values;
  // Which run each of those values came from: (run.seed, run.replicate), in the same order. Runs of
  // two points with one key share their particle sets (common/random.hpp): studies/paired.hpp pairs them.
  std::vector<ReplicateKey> j_paper_keys, j_flowing_keys, j_mid_keys;
  SampleStatistics j_paper, j_flowing, j_mid;

  AvalancheStatistics avalanches;
  ClogStatistics clogs;
  FlowDecomposition decomposition;
  RegimeFractions regime;

  double mean_sim_time_s = kNaN;
  double mean_wall_time_s = kNaN;
};

struct AnalysisOptions {
  BootstrapOptions bootstrap;       // J intervals (each J kind gets its own derived seed)
  TailCheckOptions tail;            // avalanche goodness of fit
  double hill_top_fraction = 0.2;
  double majority = 0.5;
};

// Pieces, usable on their own.
AvalancheStatistics avalanche_statistics(const std::vector<RunRecord>& runs, const TailCheckOptions& opt = {});
ClogStatistics clog_statistics(const std::vector<RunRecord>& runs, double hill_top_fraction = 0.2);
FlowDecomposition decompose_flow(const std::vector<RunRecord>& runs);
RegimeFractions regime_fractions(const std::vector<RunRecord>& runs, double majority = 0.5);

PointStatistics analyze_point(const std::vector<RunRecord>& runs, const AnalysisOptions& opt = {});

// "J with obstruction > J without": ratio of mean J of `point` to that of `baseline`.
// Paired (Pairing::when_exact; [report] pairing = "paired"): when the runs with the chosen J defined have
// exactly the same (run.seed, run.replicate) keys at both points, replicate r of the point and
// replicate r of the baseline shared their particle sets, and the comparison is the paired one
// (Fieller interval + paired t-test, common/paired_ratio.hpp; RatioComparison::paired is set).
// Otherwise, and always with Pairing::never (the default: measured pair correlations are ~0,
// README "Paired comparisons"): the independent-sample comparison (bootstrap
// interval + Welch's t-test, statistics.hpp). studies/paired.hpp has both side by side.
// Only runs where the chosen J is defined enter: J_paper exists only when every particle
// passed, so a point whose runs often clog permanently looks better than it is under
// JKind::paper -- check PointStatistics::all_passed_fraction (or regime) next to the verdict.
enum class JKind { paper, flowing, mid };
enum class Pairing { when_exact, never };
const char* to_string(JKind k);           // "J_paper", "J_flowing", "J_mid" (tables, reports)
const char* option_name(JKind k);         // "paper", "flowing", "mid": study files ([report] j) and --j
const std::vector<std::string>& jkind_option_names();  // every option_name, in enum order
std::optional<JKind> jkind_from_option(std::string_view name);
// The J statistics, values and their runs' keys of one kind.
const SampleStatistics& j_stats(const PointStatistics& s, JKind k);
const std::vector<double>& j_values(const PointStatistics& s, JKind k);
const std::vector<ReplicateKey>& j_keys(const PointStatistics& s, JKind k);

RatioComparison compare_to_baseline(const PointStatistics& point, const PointStatistics& baseline,
                                    JKind kind = JKind::paper, const BootstrapOptions& opt = {},
                                    Pairing pairing = Pairing::never);

}  // namespace gapflow

// RunRecord: everything one simulation run reports, whatever the model.
// Built by GapMonitor::finish() (measurement.hpp); written as JSON by write_json.
#pragma once

#include <cstdint>
#include <iosfwd>
#include <optional>
#include <string>
#include <vector>

namespace gapflow {

struct Crossing {
  int id = 0;       // particle index
  double t = 0;     // s after release, interpolated within the step
  double x = 0;     // m, where it crossed the gap line (plane frame)
};

// Crossings separated by less than the clog timeout.
struct Avalanche {
  int size = 0;           // particles
  double t_start = 0;     // s, first crossing
  double t_end = 0;       // s, last crossing
  bool first = false;     // started from the initial packing (usually discarded)
  bool censored = false;  // not ended by a clog (run ended while flowing, or no particles left)
};

// A gap of at least clog_timeout_s without a crossing.
struct Clog {
  double t_start = 0;     // s, last crossing before the clog (or release)
  double duration = 0;    // s, until the next crossing (or run end)
  bool censored = false;  // the run ended before the clog broke
  // m, where the flow stopped: the distance from the gap centre to the nearest
  // particle on the board when the clog was detected (clog_timeout_s after it
  // began, before any protocol acts). An arch at the gap keeps a particle within
  // W/2 + d (clog_at_gap); a clog upstream (e.g. between obstruction and walls)
  // leaves the gap's mouth empty. Empty for records made before it was measured.
  std::optional<double> front_m = std::nullopt;
  // Whether the arch leans on the obstruction at detection: a chain of touching front
  // particles (those the gap line sees) links it to a wall and none links the two walls
  // without it (front_leans_on_obstruction, common/clog_front.hpp). False without an
  // obstruction; empty for records made before it was measured.
  std::optional<bool> on_obstruction = std::nullopt;
};

// Where a clog formed (clog_site in common/measurement.hpp).
enum class ClogSite { gap, obstruction, upstream };

enum class Regime { continuous, intermittent, clogged };
enum class EndReason { all_passed, n_passed, time_limit, permanent_clog };

const char* to_string(Regime r);
const char* to_string(EndReason r);

struct RunRecord {
  // Identity.
  std::string model;                 // "2d" or "3d"
  std::string scenario_name;
  std::uint64_t scenario_hash = 0;
  std::uint64_t base_seed = 0;
  int replicate = 0;
  std::uint64_t run_seed = 0;
  double time_step_s = 0;            // s (lab)

  // Geometry (for the dimensionless form).
  double diameter_m = 0;             // nominal d
  double gap_m = 0;                  // W
  double distance_m = 0;             // D (0 without obstruction)
  double incline_rad = 0;

  // Counts.
  int particles = 0;                 // N
  int passed = 0;                    // crossings of the gap line (> N possible with re-injection)
  int reinjected = 0;                // passed particles put back on the pile (protocol.reinject_passed)
  int perturbations = 0;             // clog-breaking interventions (protocol.clog_breaking)
  int escaped = 0;                   // left the domain anywhere but the gap (tunnelling); must be 0
  int max_conservation_error = 0;    // max over steps of |passed + inside + escaped - N|; must be 0

  // Time.
  double sim_time_s = 0;             // s simulated after release
  double wall_time_s = 0;            // s of wall clock for the whole run (including settling)
  EndReason end_reason = EndReason::time_limit;
  Regime regime = Regime::continuous;

  // Flow rates, particles/s. Missing when undefined.
  std::optional<double> j_paper;     // N / time for all to pass (all passed, or all but run.stranded_max stopped for good)
  std::optional<double> j_flowing;   // crossings per second of flowing time (clogs removed)
  std::optional<double> j_mid;       // rate between the 10 % and 90 % crossings

  std::vector<Crossing> crossings;
  std::vector<Avalanche> avalanches;
  std::vector<Clog> clogs;

  // Dimensionless J*sqrt(d/g), g = 9.81 m/s^2.
  std::optional<double> j_paper_star() const;
  std::optional<double> j_flowing_star() const;
  double sim_per_wall() const { return wall_time_s > 0 ? sim_time_s / wall_time_s : 0; }
};

// False for a run whose store kept its summary but not its crossing times (a store slimmed by
// scripts/slim_store.py): spheres passed and no crossing row is left.
inline bool crossings_stored(const RunRecord& r) { return r.passed == 0 || !r.crossings.empty(); }

void write_json(std::ostream& out, const RunRecord& r);
// One-screen summary for people.
// Why a finished run is not a valid discharge, or nothing: particles that left the
// board elsewhere than through the gap (tunnelling, or walls shaken hard enough to
// fling them out) make every J and the regime meaningless.
std::optional<std::string> invalid_run_reason(const RunRecord& r);
void write_summary(std::ostream& out, const RunRecord& r);

}  // namespace gapflow

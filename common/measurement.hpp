// Engine-independent measurement: the gap-line crossing of each particle (once),
// escapes through walls, and the run record built from the crossings.
// Both models feed it particle positions after every step; neither keeps a
// second copy of this logic.
#pragma once

#include "common/geometry.hpp"
#include "common/run_record.hpp"

#include <optional>
#include <vector>

namespace gapflow {

enum class ParticleFate { inside, passed_retire, passed_keep, escaped };

class GapMonitor {
 public:
  explicit GapMonitor(const CompiledScenario& scenario);

  // Report the position (plane frame, lab metres) of an active particle after a
  // step that ended at time t (s after release). Returns what the model should
  // do with it: keep simulating, or retire it (remove the body) because it has
  // passed and is well below the gap, or because it escaped.
  ParticleFate observe(int id, Vec2 position, double t);

  // Called once per step after all observe() calls.
  void end_step(double t);

  // A particle was moved by a protocol (common/protocols.hpp) to `position`: a
  // passed particle becomes inside again (it may cross again); an inside one
  // just jumps (no crossing is inferred from the jump).
  void reinject(int id, Vec2 position);
  bool is_inside(int id) const {
    const State& s = state_[static_cast<size_t>(id)];
    return !s.passed && !s.escaped;
  }

  int passed() const { return passed_; }   // crossings so far (a re-injected particle can cross again)
  int away() const { return away_; }       // passed and not (yet) re-injected
  int reinjected() const { return reinjected_; }
  int escaped() const { return escaped_; }
  int inside() const { return inside_; }  // as of the last end_step()
  int particles() const { return static_cast<int>(state_.size()); }
  double last_crossing_time() const { return last_crossing_t_; }
  const std::vector<Crossing>& crossings() const { return crossings_; }

  // Fill the measurement part of a record (counts, crossings, avalanches, clogs
  // with where each one formed, J, regime).
  void finish(double t_end, EndReason reason, RunRecord& record) const;

 private:
  struct ClogFront {
    double t_start = 0;  // s, the last crossing before the clog (as Clog::t_start)
    double front_m = 0;           // m, nearest particle on the board to the gap centre at detection
    bool on_obstruction = false;  // the front's arch leans on the obstruction (common/clog_front.hpp)
  };
  void locate_clog(double t);
  double nearest_to_gap_m() const;
  bool front_on_obstruction(double t) const;

  struct State {
    bool seen = false;
    bool passed = false;
    bool escaped = false;
    Vec2 last;  // m, position at the previous observation
  };
  const CompiledScenario& sc_;
  std::vector<State> state_;
  std::vector<Crossing> crossings_;
  int passed_ = 0;
  int away_ = 0;
  int reinjected_ = 0;
  int escaped_ = 0;
  int inside_ = 0;             // observed this step, neither passed nor escaped
  int inside_this_step_ = 0;
  int max_conservation_error_ = 0;
  double t_prev_ = 0;          // s, end of the previous step
  double last_crossing_t_ = 0;
  double retire_depth_ = 0;    // m below the gap line where passed particles are removed
  double gap_tolerance_ = 0;   // m, how far outside |x| = W/2 a crossing may lie (shaking moves the tips)
  std::vector<ClogFront> clog_fronts_;  // one per quiet period of at least clog_timeout_s
};

// The classification of a clog's front (Clog::front_m): at the gap if a particle
// on the board is within W/2 + d of the gap centre (every arch across the gap
// has its feet there), upstream otherwise (the mouth ran empty: the flow stopped
// further up, e.g. between an obstruction and the walls).
bool clog_at_gap(double front_m, double gap_m, double diameter_m);

// Where a clog formed, from what was measured at its detection (empty if its front
// was not measured):
//  * obstruction: the arch leans on the obstruction (Clog::on_obstruction,
//    front_leans_on_obstruction): the flow stopped between the obstruction and the
//    walls, wherever that is; with the obstruction within reach of the gap this is the
//    only way to tell it from an arch across the gap, since both keep the mouth occupied;
//  * gap: otherwise, when the gap's mouth is occupied (clog_at_gap);
//  * upstream: otherwise (the mouth ran empty and the arch does not lean on the obstruction).
// A record made before on_obstruction was measured is classified by its front alone (gap or upstream).
std::optional<ClogSite> clog_site(const Clog& clog, double gap_m, double diameter_m);

// Stop rule shared by both models.
struct StopDecision {
  bool stop = false;
  EndReason reason = EndReason::time_limit;
};
StopDecision should_stop(const RunDef& run, const GapMonitor& monitor, double t);

// Avalanches and clogs from sorted crossing times (exposed for tests/statistics).
// A gap of at least clog_timeout_s without a crossing (counted from release) is a clog.
void segment_flow(const std::vector<Crossing>& crossings, double clog_timeout_s, double t_end,
                  std::vector<Avalanche>& avalanches, std::vector<Clog>& clogs);

}  // namespace gapflow

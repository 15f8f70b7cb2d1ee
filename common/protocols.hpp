// Clog-breaking and re-injection protocols ([protocol] in the scenario).
//
// The paper breaks clogs by shaking (the [shaking.*] schedules, applied by the
// driver). Two more protocols from the 2D clogging literature (Goldberg,
// Carlevaro & Pugnaloni 2018) act when no particle has crossed for
// run.clog_timeout_s:
//  * local_perturbation: the particles with a free line of sight to the gap
//    centre (the arch and its neighbours, within W/2 + perturb_radius_d d) are
//    lifted onto the top of the pile;
//  * refill: every particle still on the board goes back to its initial
//    packing site, at rest.
// And reinject_passed puts each passed particle back on top of the pile, so
// that one run yields thousands of avalanches at a steady head.
#pragma once

#include "common/engine_session.hpp"
#include "common/measurement.hpp"
#include "common/random.hpp"

#include <vector>

namespace gapflow {

class ClogProtocol {
 public:
  explicit ClogProtocol(const CompiledScenario& scenario);

  bool reinjects_passed() const { return sc_.def.protocol.reinject_passed; }

  // After the step's measurement. `active` are this step's positions;
  // `passed_below` the passed particles that are far below the gap (re-injected
  // when reinject_passed, otherwise the driver retires them).
  void apply(double t, EngineSession& session, GapMonitor& monitor, const std::vector<ActiveParticle>& active,
             const std::vector<int>& passed_below);

  int perturbations() const { return perturbations_; }

  // Free sites for `count` particles (lab metres): lattice rows from the top of
  // the initial packing upward, shuffled within a row, clear of every particle on the board.
  std::vector<Vec2> sites_on_top(const std::vector<ActiveParticle>& on_board, std::size_t count);
  // The particles (ids) within W/2 + perturb_radius_d d of the gap centre with a free line of
  // sight to it past the other particles (visible_from in common/clog_front.hpp; the
  // obstruction is not an occluder here).
  std::vector<int> gap_blockers(const std::vector<ActiveParticle>& on_board) const;

 private:
  void move(EngineSession& session, GapMonitor& monitor, const std::vector<int>& ids, const std::vector<Vec2>& to);
  void break_clog(EngineSession& session, GapMonitor& monitor, const std::vector<ActiveParticle>& on_board);

  const CompiledScenario& sc_;
  RandomStream rng_;              // run_stream(run_seed, perturbation): deterministic per run
  double last_intervention_ = 0;  // s, time of the last clog-breaking intervention
  int perturbations_ = 0;
};

}  // namespace gapflow

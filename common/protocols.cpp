#include "common/protocols.hpp"

#include "common/clog_front.hpp"
#include "common/vec2_math.hpp"

#include <algorithm>
#include <fmt/format.h>
#include <cmath>
#include <stdexcept>

namespace gapflow {

ClogProtocol::ClogProtocol(const CompiledScenario& sc)
    : sc_(sc), rng_(run_stream(sc.run_seed, StreamPurpose::perturbation)) {}

namespace {

double radius_of(const CompiledScenario& sc, int id) { return sc.particles[static_cast<size_t>(id)].diameter / 2; }

std::vector<ActiveParticle> on_board(const std::vector<ActiveParticle>& active, const GapMonitor& m) {
  std::vector<ActiveParticle> out;
  for (const ActiveParticle& p : active)
    if (m.is_inside(p.id)) out.push_back(p);
  return out;
}

}  // namespace

std::vector<Vec2> ClogProtocol::sites_on_top(const std::vector<ActiveParticle>& board, std::size_t count) {
  // Rows start at the top of the initial packing (a steady head), not above the
  // highest particle: particles still rolling down from an earlier injection
  // would otherwise ratchet the injection height up to the top wall.
  const double d_max = sc_.nominal_diameter * (1 + sc_.def.particles.size_scatter);
  const double a = d_max * (1 + sc_.def.release.lattice_gap);
  double start = sc_.barrier_y;
  for (const ParticleSeed& p : sc_.particles) start = std::max(start, p.position.y);
  auto free = [&](Vec2 s, const std::vector<Vec2>& taken) {
    for (const ActiveParticle& p : board)
      if (length(p.position - s) < a / 2 + radius_of(sc_, p.id)) return false;
    for (Vec2 t : taken)
      if (length(t - s) < a) return false;
    return fits_on_board(sc_, s, a / 2);
  };
  std::vector<Vec2> sites;
  for (int row = 0; sites.size() < count; ++row) {
    const double y = start + row * a * std::sqrt(3.0) / 2;
    if (y > sc_.plane_length - a / 2)
      throw std::runtime_error(fmt::format("no room on the board to re-inject {} particles above y = {:.3f} m: "
                                           "lengthen plane.length_mm",
                                           count, start));
    std::vector<Vec2> row_sites;
    const double offset = (row % 2) ? a / 2 : 0.0;
    const int half = static_cast<int>(std::ceil(sc_.channel_width / 2 / a)) + 1;
    for (int j = -half; j <= half; ++j) row_sites.push_back({j * a + offset, y});
    // Shuffle (Fisher-Yates) so that re-injected particles do not pile up on one side.
    for (size_t i = row_sites.size(); i > 1; --i)
      std::swap(row_sites[i - 1], row_sites[static_cast<size_t>(rng_.next_u64() % i)]);
    for (Vec2 s : row_sites)
      if (sites.size() < count && free(s, sites)) sites.push_back(s);
  }
  return sites;
}

std::vector<int> ClogProtocol::gap_blockers(const std::vector<ActiveParticle>& board) const {
  const double reach = sc_.gap / 2 + sc_.def.protocol.perturb_radius_d * sc_.nominal_diameter;
  std::vector<BoardDisc> near;
  for (const ActiveParticle& p : board)
    if (length(p.position) <= reach) near.push_back({p.id, p.position, radius_of(sc_, p.id)});
  // Only the discs hide one another here, as when the protocol was first run (the clogging
  // studies, without an obstruction): the obstruction hides nothing from this protocol.
  return visible_from(ObstructionGeometry{}, near, Vec2{0, 0});
}

void ClogProtocol::move(EngineSession& session, GapMonitor& monitor, const std::vector<int>& ids,
                        const std::vector<Vec2>& to) {
  std::vector<ActiveParticle> placements;
  for (size_t i = 0; i < ids.size(); ++i) {
    placements.push_back({ids[i], to[i]});
    monitor.reinject(ids[i], to[i]);
  }
  session.reinject(placements);
}

void ClogProtocol::break_clog(EngineSession& session, GapMonitor& monitor, const std::vector<ActiveParticle>& board) {
  std::vector<int> ids;
  std::vector<Vec2> to;
  if (sc_.def.protocol.clog_breaking == ClogBreaking::local_perturbation) {
    ids = gap_blockers(board);
    std::vector<ActiveParticle> staying;
    for (const ActiveParticle& p : board)
      if (std::find(ids.begin(), ids.end(), p.id) == ids.end()) staying.push_back(p);
    to = sites_on_top(staying, ids.size());
  } else {  // refill: every particle on the board back to its own initial packing site
    for (const ActiveParticle& p : board) {
      ids.push_back(p.id);
      to.push_back(sc_.particles[static_cast<size_t>(p.id)].position);
    }
  }
  move(session, monitor, ids, to);
}

void ClogProtocol::apply(double t, EngineSession& session, GapMonitor& monitor,
                         const std::vector<ActiveParticle>& active, const std::vector<int>& passed_below) {
  const ProtocolDef& p = sc_.def.protocol;
  if (p.reinject_passed && !passed_below.empty()) {
    const std::vector<ActiveParticle> board = on_board(active, monitor);
    move(session, monitor, passed_below, sites_on_top(board, passed_below.size()));
  }
  if (p.clog_breaking == ClogBreaking::shaking) return;
  const double quiet_since = std::max(monitor.last_crossing_time(), last_intervention_);
  if (t - quiet_since < sc_.def.run.clog_timeout_s) return;
  break_clog(session, monitor, on_board(active, monitor));
  last_intervention_ = t;
  ++perturbations_;
}

}  // namespace gapflow

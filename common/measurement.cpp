#include "common/measurement.hpp"

#include "common/clog_front.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace gapflow {

GapMonitor::GapMonitor(const CompiledScenario& scenario) : sc_(scenario) {
  state_.resize(scenario.particles.size());
  for (size_t i = 0; i < state_.size(); ++i) state_[i].last = scenario.particles[i].position;
  inside_ = static_cast<int>(state_.size());
  // Three diameters below the gap a passed particle can no longer touch anything
  // that matters for the flow: remove it, so that the engines stop paying for it.
  retire_depth_ = 3 * scenario.nominal_diameter;
  // Shaken walls move their tips by up to the amplitude; 1 um more for round-off.
  const ShakeDef& walls = scenario.def.shaking.walls;
  gap_tolerance_ = (walls.enabled ? walls.amplitude_mm * 1e-3 : 0.0) + 1e-6;
}

namespace {

bool outside_domain(const CompiledScenario& c, Vec2 p) {
  if (!std::isfinite(p.x) || !std::isfinite(p.y)) return true;
  if (std::abs(p.x) > c.channel_width / 2) return true;  // through a retaining wall
  if (p.y > c.plane_length) return true;                 // through the top wall
  // Behind a bottleneck wall (deeper than the wall is thick): tunnelled through it.
  if (p.y >= 0 && p.y <= c.funnel_height + c.wall_thickness &&
      clearance_to_bottleneck_walls(c, p) < -c.wall_thickness)
    return true;
  return false;
}

}  // namespace

ParticleFate GapMonitor::observe(int id, Vec2 p, double t) {
  State& s = state_[static_cast<size_t>(id)];
  if (s.escaped) return ParticleFate::escaped;
  if (s.passed) return p.y < -retire_depth_ ? ParticleFate::passed_retire : ParticleFate::passed_keep;

  if (p.y < 0 && s.last.y >= 0 && std::isfinite(p.x)) {
    // Interpolate the crossing within the step: the gap line is crossed once.
    const double f = s.last.y / (s.last.y - p.y);
    const double tc = t_prev_ + f * (t - t_prev_);
    const double xc = s.last.x + f * (p.x - s.last.x);
    if (std::abs(xc) <= sc_.gap / 2 + gap_tolerance_) {
      s.passed = true;
      ++passed_;
      ++away_;
      crossings_.push_back({id, tc, xc});
      last_crossing_t_ = std::max(last_crossing_t_, tc);
      s.last = p;
      return p.y < -retire_depth_ ? ParticleFate::passed_retire : ParticleFate::passed_keep;
    }
    s.escaped = true;  // crossed the gap line beside the gap: through a bottleneck wall
  } else if (outside_domain(sc_, p)) {
    s.escaped = true;
  }
  if (s.escaped) {
    ++escaped_;
    return ParticleFate::escaped;
  }
  s.last = p;
  ++inside_this_step_;
  return ParticleFate::inside;
}

void GapMonitor::reinject(int id, Vec2 position) {
  State& s = state_[static_cast<size_t>(id)];
  if (s.passed) {
    s.passed = false;
    --away_;
    ++inside_;  // inside again as of now; the next end_step() recounts
    ++reinjected_;
  }
  s.last = position;
}

void GapMonitor::end_step(double t) {
  inside_ = inside_this_step_;
  const int error = std::abs(inside_ + away_ + escaped_ - particles());
  max_conservation_error_ = std::max(max_conservation_error_, error);
  inside_this_step_ = 0;
  t_prev_ = t;
  locate_clog(t);
}

double GapMonitor::nearest_to_gap_m() const {
  double nearest = std::numeric_limits<double>::infinity();
  for (const State& s : state_)
    if (!s.passed && !s.escaped) nearest = std::min(nearest, std::hypot(s.last.x, s.last.y));
  return nearest;
}

bool GapMonitor::front_on_obstruction(double t) const {
  if (sc_.obstruction.shape == ObstructionShape::none) return false;
  std::vector<BoardDisc> board;
  for (size_t i = 0; i < state_.size(); ++i)
    if (!state_[i].passed && !state_[i].escaped)
      board.push_back({static_cast<int>(i), state_[i].last, sc_.particles[i].diameter / 2});
  // The engines put the shaken walls and obstruction on schedule at the end of each step.
  return front_leans_on_obstruction(sc_, board, shake_offsets(sc_.def.shaking, t));
}

// Once per quiet period, at the step that makes it a clog: the positions are this
// step's, before a protocol moves anything (the driver calls end_step first).
void GapMonitor::locate_clog(double t) {
  if (t - last_crossing_t_ < sc_.def.run.clog_timeout_s) return;
  if (!clog_fronts_.empty() && clog_fronts_.back().t_start == last_crossing_t_) return;
  if (inside_ == 0) return;  // nothing left on the board: the discharge ended, not a clog
  clog_fronts_.push_back({last_crossing_t_, nearest_to_gap_m(), front_on_obstruction(t)});
}

bool clog_at_gap(double front_m, double gap_m, double diameter_m) { return front_m <= gap_m / 2 + diameter_m; }

std::optional<ClogSite> clog_site(const Clog& c, double gap_m, double diameter_m) {
  if (!c.front_m) return std::nullopt;
  if (c.on_obstruction.value_or(false)) return ClogSite::obstruction;
  return clog_at_gap(*c.front_m, gap_m, diameter_m) ? ClogSite::gap : ClogSite::upstream;
}

void segment_flow(const std::vector<Crossing>& crossings, double clog_timeout_s, double t_end,
                  std::vector<Avalanche>& avalanches, std::vector<Clog>& clogs) {
  avalanches.clear();
  clogs.clear();
  double previous = 0.0;  // release
  bool open = false;
  for (const Crossing& c : crossings) {
    const double wait = c.t - previous;
    if (wait >= clog_timeout_s) {
      clogs.push_back({previous, wait, false});
      open = false;  // the current avalanche (if any) ended in this clog
    }
    if (!open) {
      avalanches.push_back({0, c.t, c.t, avalanches.empty(), false});
      open = true;
    }
    Avalanche& a = avalanches.back();
    ++a.size;
    a.t_end = c.t;
    previous = c.t;
  }
  const double tail = t_end - previous;
  if (tail >= clog_timeout_s) {
    clogs.push_back({previous, tail, true});  // the run ended before this clog broke
  } else if (open) {
    avalanches.back().censored = true;  // the run ended while flowing (or nothing was left)
  }
}

void GapMonitor::finish(double t_end, EndReason reason, RunRecord& r) const {
  r.particles = particles();
  r.passed = passed_;
  r.reinjected = reinjected_;
  r.escaped = escaped_;
  r.max_conservation_error = max_conservation_error_;
  r.sim_time_s = t_end;
  r.end_reason = reason;
  r.crossings = crossings_;
  std::stable_sort(r.crossings.begin(), r.crossings.end(),
                   [](const Crossing& a, const Crossing& b) { return a.t < b.t; });
  segment_flow(r.crossings, sc_.def.run.clog_timeout_s, t_end, r.avalanches, r.clogs);

  const auto n = static_cast<int>(r.crossings.size());
  r.j_paper.reset();
  r.j_flowing.reset();
  r.j_mid.reset();
  // The paper's J needs a board that emptied once; up to run.stranded_max particles
  // may stay behind (J is then over those that passed, N_passed / t_last). The end
  // reason does not matter: with stop_after_no_flow_s = 20 s a stranded run often
  // reaches the time limit before it is declared clogged.
  const int left_behind = particles() - passed_;
  const bool emptied = n > 0 && reinjected_ == 0 && left_behind <= sc_.def.run.stranded_max;
  if (emptied) r.j_paper = n / r.crossings.back().t;
  // The wait after the last crossing of an emptied board is not a clog of the flow:
  // the discharge ended there, as if the stranded spheres had passed.
  if (emptied && left_behind > 0 && !r.clogs.empty() && r.clogs.back().censored) {
    r.clogs.pop_back();
    if (!r.avalanches.empty()) r.avalanches.back().censored = true;
  }
  // Where each clog formed: matched by its start (both are the same crossing time).
  for (Clog& c : r.clogs)
    for (const ClogFront& f : clog_fronts_)
      if (f.t_start == c.t_start) {
        c.front_m = f.front_m;
        c.on_obstruction = f.on_obstruction;
      }
  // Rate while flowing: the crossing intervals inside avalanches only. A clog's
  // duration runs from crossing to crossing, so it must not also remove an interval.
  int intervals = 0;
  double flowing = 0;
  for (const Avalanche& a : r.avalanches) {
    intervals += a.size - 1;
    flowing += a.t_end - a.t_start;
  }
  if (intervals > 0 && flowing > 0) r.j_flowing = intervals / flowing;
  if (n >= 10) {
    const int i10 = static_cast<int>(std::floor(0.1 * (n - 1)));
    const int i90 = static_cast<int>(std::ceil(0.9 * (n - 1)));
    const double dt = r.crossings[i90].t - r.crossings[i10].t;
    if (dt > 0) r.j_mid = (i90 - i10) / dt;
  }
  if (reason == EndReason::permanent_clog && !emptied)
    r.regime = Regime::clogged;
  else
    r.regime = r.clogs.empty() ? Regime::continuous : Regime::intermittent;
}

StopDecision should_stop(const RunDef& run, const GapMonitor& m, double t) {
  if (m.away() + m.escaped() >= m.particles()) return {true, EndReason::all_passed};
  if (run.end == EndCondition::n_passed && m.passed() >= run.n_passed) return {true, EndReason::n_passed};
  if (t >= run.time_limit_s - 1e-12) return {true, EndReason::time_limit};
  if (run.stop_after_no_flow_s > 0 && t - m.last_crossing_time() >= run.stop_after_no_flow_s)
    return {true, EndReason::permanent_clog};
  return {};
}

}  // namespace gapflow

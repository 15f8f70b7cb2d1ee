#include "common/run_record.hpp"

#include "common/steady_state.hpp"
#include "common/units.hpp"

#include <fmt/format.h>
#include <ostream>
#include <toml++/toml.h>

namespace gapflow {

const char* to_string(Regime r) {
  switch (r) {
    case Regime::continuous: return "continuous";
    case Regime::intermittent: return "intermittent";
    case Regime::clogged: return "clogged";
  }
  return "?";
}

const char* to_string(EndReason r) {
  switch (r) {
    case EndReason::all_passed: return "all_passed";
    case EndReason::n_passed: return "n_passed";
    case EndReason::time_limit: return "time_limit";
    case EndReason::permanent_clog: return "permanent_clog";
  }
  return "?";
}

std::optional<double> RunRecord::j_paper_star() const {
  if (!j_paper) return std::nullopt;
  return dimensionless_flow_rate(*j_paper, diameter_m);
}

std::optional<double> RunRecord::j_flowing_star() const {
  if (!j_flowing) return std::nullopt;
  return dimensionless_flow_rate(*j_flowing, diameter_m);
}

namespace {

std::string hex(std::uint64_t v) { return fmt::format("{:016x}", v); }

void put_optional(toml::table& t, const char* key, const std::optional<double>& v) {
  if (v) t.insert(key, *v);  // JSON has no NaN: an undefined rate is simply absent
}

toml::table crossings_table(const std::vector<Crossing>& cs) {
  toml::array id, t, x;
  for (const Crossing& c : cs) {
    id.push_back(c.id);
    t.push_back(c.t);
    x.push_back(c.x);
  }
  return toml::table{{"id", id}, {"t_s", t}, {"x_m", x}};
}

toml::array avalanches_array(const std::vector<Avalanche>& as) {
  toml::array out;
  for (const Avalanche& a : as)
    out.push_back(toml::table{{"size", a.size}, {"t_start_s", a.t_start}, {"t_end_s", a.t_end},
                              {"first", a.first}, {"censored", a.censored}});
  return out;
}

toml::array clogs_array(const std::vector<Clog>& cs) {
  toml::array out;
  for (const Clog& c : cs) {
    toml::table t{{"t_start_s", c.t_start}, {"duration_s", c.duration}, {"censored", c.censored}};
    if (c.front_m) t.insert("front_m", *c.front_m);
    if (c.on_obstruction) t.insert("on_obstruction", *c.on_obstruction);
    out.push_back(std::move(t));
  }
  return out;
}

// J_steady of a re-injected run (common/steady_state.hpp), derived from the crossings: the
// same numbers whether the record comes from a run or from a store.
void put_steady_state(toml::table& t, const RunRecord& r) {
  const std::optional<SteadyStateEstimate> e = steady_state_of(r);
  if (!e) return;
  toml::table s{{"valid", e->valid}};
  if (!e->valid) s.insert("why_not", e->why_not);
  s.insert("truncation_s", e->truncation_s);
  s.insert("transient_at_limit", e->transient_at_limit);
  s.insert("window_s", e->window_s);
  s.insert("crossings", e->crossings);
  s.insert("clogged_s", e->clogged_s);
  if (e->valid) {
    t.insert("j_steady_per_s", e->j_per_s);
    s.insert("j_per_s", e->j_per_s);
    s.insert("half_width_95_per_s", e->half_width_per_s);
    s.insert("batches", e->batches);
    s.insert("batch_s", e->batch_s);
    s.insert("lag1_autocorrelation", e->lag1_autocorrelation);
    s.insert("autocorrelated", e->autocorrelated);
  }
  t.insert("steady_state", std::move(s));
}

}  // namespace

void write_json(std::ostream& out, const RunRecord& r) {
  toml::table t{
      {"model", r.model},
      {"scenario", r.scenario_name},
      {"scenario_hash", hex(r.scenario_hash)},
      {"base_seed", static_cast<std::int64_t>(r.base_seed)},
      {"replicate", r.replicate},
      {"run_seed", hex(r.run_seed)},
      {"time_step_s", r.time_step_s},
      {"diameter_m", r.diameter_m},
      {"gap_m", r.gap_m},
      {"distance_m", r.distance_m},
      {"incline_rad", r.incline_rad},
      {"w_over_d", r.gap_m / r.diameter_m},
      {"distance_over_d", r.distance_m / r.diameter_m},  // D/d
      {"particles", r.particles},
      {"passed", r.passed},
      {"reinjected", r.reinjected},
      {"perturbations", r.perturbations},
      {"escaped", r.escaped},
      {"max_conservation_error", r.max_conservation_error},
      {"sim_time_s", r.sim_time_s},
      {"wall_time_s", r.wall_time_s},
      {"sim_per_wall", r.sim_per_wall()},
      {"end_reason", to_string(r.end_reason)},
      {"regime", to_string(r.regime)},
      {"crossings", crossings_table(r.crossings)},
      {"avalanches", avalanches_array(r.avalanches)},
      {"clogs", clogs_array(r.clogs)},
  };
  put_optional(t, "j_paper_per_s", r.j_paper);
  put_optional(t, "j_flowing_per_s", r.j_flowing);
  put_optional(t, "j_mid_per_s", r.j_mid);
  put_optional(t, "j_paper_star", r.j_paper_star());
  put_optional(t, "j_flowing_star", r.j_flowing_star());
  put_steady_state(t, r);
  out << toml::json_formatter{t} << "\n";
}

namespace {
std::string rate(const std::optional<double>& j, double d) {
  if (!j) return "n/a";
  return fmt::format("{:8.2f} /s   J*sqrt(d/g) = {:.4f}", *j, dimensionless_flow_rate(*j, d));
}
}  // namespace

std::optional<std::string> invalid_run_reason(const RunRecord& r) {
  if (r.escaped == 0) return std::nullopt;
  return fmt::format("{} of {} particles escaped (left the board elsewhere than through the gap): this run is not a "
                     "discharge, and its J and regime mean nothing",
                     r.escaped, r.particles);
}

void write_summary(std::ostream& out, const RunRecord& r) {
  int clogs_complete = 0;
  for (const Clog& c : r.clogs) clogs_complete += c.censored ? 0 : 1;
  out << fmt::format("scenario      {}  (model {}, seed {}, replicate {}, run seed {:016x})\n", r.scenario_name,
                     r.model, r.base_seed, r.replicate, r.run_seed);
  out << fmt::format("geometry      d = {:.2f} mm   W = {:.1f} mm   W/d = {:.3f}   D/d = {:.3f}\n",
                     r.diameter_m * 1e3, r.gap_m * 1e3, r.gap_m / r.diameter_m, r.distance_m / r.diameter_m);
  out << fmt::format("passed        {} of {}   escaped {}   end: {}   regime: {}\n", r.passed, r.particles,
                     r.escaped, to_string(r.end_reason), to_string(r.regime));
  out << fmt::format("J (paper)     {}   [N / time for all to pass]\n", rate(r.j_paper, r.diameter_m));
  out << fmt::format("J (flowing)   {}   [clogs removed]\n", rate(r.j_flowing, r.diameter_m));
  out << fmt::format("J (10-90 %)   {}\n", rate(r.j_mid, r.diameter_m));
  if (const std::optional<SteadyStateEstimate> e = steady_state_of(r)) out << steady_state_line(*e) << "\n";
  out << fmt::format("clogs         {} ended, {} unbroken at the end   avalanches {}\n", clogs_complete,
                     r.clogs.size() - clogs_complete, r.avalanches.size());
  out << fmt::format("time          {:.2f} s simulated in {:.2f} s wall = {:.2f} simulated s per wall s (dt = {:g} s)\n",
                     r.sim_time_s, r.wall_time_s, r.sim_per_wall(), r.time_step_s);
  if (auto why = invalid_run_reason(r)) out << "INVALID       " << *why << "\n";
}

}  // namespace gapflow

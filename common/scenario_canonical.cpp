// Canonical scenario text: every resolved value of a ScenarioDef, written in one
// fixed order and spelling, so that two scenarios that simulate the same thing
// read the same; scenario_hash is a hash of it and keys every stored run.
#include "common/random.hpp"
#include "common/scenario_loader.hpp"
#include "common/toml_spelling.hpp"

#include <fmt/format.h>

#include <cstdint>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace gapflow {

namespace {

class TomlWriter {
 public:
  void section(std::string_view name) { out_ += fmt::format("{}[{}]\n", out_.empty() ? "" : "\n", name); }
  void put(std::string_view key, double v) { line(key, toml_double(v)); }
  void put(std::string_view key, bool v) { line(key, v ? "true" : "false"); }
  void put(std::string_view key, int v) { line(key, std::to_string(v)); }
  void put(std::string_view key, std::uint64_t v) { line(key, std::to_string(v)); }
  void put(std::string_view key, const std::string& v) { line(key, toml_quote(v)); }
  void put(std::string_view key, const char* v) { line(key, toml_quote(v)); }
  void put(std::string_view key, const std::vector<Vec2>& v) {
    std::string s = "[";
    for (std::size_t i = 0; i < v.size(); ++i)
      s += fmt::format("{}[{}, {}]", i ? ", " : "", toml_double(v[i].x), toml_double(v[i].y));
    line(key, s + "]");
  }
  std::string str() && { return std::move(out_); }

 private:
  void line(std::string_view key, const std::string& value) { out_ += fmt::format("{} = {}\n", key, value); }
  std::string out_;
};

void write_shake(TomlWriter& w, std::string_view name, const ShakeDef& k) {
  w.section(name);
  w.put("enabled", k.enabled);
  w.put("amplitude_mm", k.amplitude_mm);
  w.put("direction_deg", k.direction_deg);
  w.put("mirror", k.mirror);
  w.put("decay_s", k.decay_s);
  w.put("period_s", k.period_s);
  w.put("start_s", k.start_s);
  w.put("frequency_hz", k.frequency_hz);
}

void write_head(TomlWriter& w, const ScenarioDef& d) {
  w.section("scenario");
  w.put("name", d.name);
  w.put("description", d.description);
  w.section("plane");
  w.put("incline_deg", d.plane.incline_deg);
  w.put("length_mm", d.plane.length_mm);
  w.put("width_mm", d.plane.width_mm);
  // Keys added after results were stored are written only when set, so that older hashes stay valid.
  if (d.plane.lateral_tilt_deg != 0) w.put("lateral_tilt_deg", d.plane.lateral_tilt_deg);
  if (d.plane.cover_gap_mm != 0) w.put("cover_gap_mm", d.plane.cover_gap_mm);
  w.section("bottleneck");
  w.put("wall_angle_deg", d.bottleneck.wall_angle_deg);
  w.put("gap_mm", d.bottleneck.gap_mm);
  w.put("wall_thickness_mm", d.bottleneck.wall_thickness_mm);
  if (d.bottleneck.gap_offset_mm != 0) w.put("gap_offset_mm", d.bottleneck.gap_offset_mm);
}

void write_particles(TomlWriter& w, const ParticlesDef& p, const ReleaseDef& r) {
  w.section("particles");
  w.put("count", p.count);
  w.put("diameter_mm", p.diameter_mm);
  w.put("size_scatter", p.size_scatter);
  w.put("size_distribution", to_string(p.size_distribution));
  w.put("density_kg_m3", p.density_kg_m3);
  w.put("friction_particle", p.friction_particle);
  w.put("friction_wall", p.friction_wall);
  w.put("friction_base", p.friction_base);
  w.put("restitution", p.restitution);
  w.put("rolling_resistance", p.rolling_resistance);
  w.put("spinning_friction_mm", p.spinning_friction_mm);
  if (p.drag_per_s != 0) w.put("drag_per_s", p.drag_per_s);
  if (p.quadratic_drag_per_m != 0) w.put("quadratic_drag_per_m", p.quadratic_drag_per_m);
  w.section("release");
  w.put("barrier_mm", r.barrier_mm);
  w.put("settle_s", r.settle_s);
  w.put("lattice_gap", r.lattice_gap);
}

void write_obstruction(TomlWriter& w, const ObstructionDef& o) {
  w.section("obstruction");
  // The preset is spelt as the shape so that it survives the round trip.
  bool preset = o.shape == ObstructionShape::triangle && (o.preset == "A" || o.preset == "V");
  w.put("shape", preset ? o.preset : std::string(to_string(o.shape)));
  w.put("diameter_mm", o.diameter_mm);
  w.put("side_mm", o.side_mm);
  w.put("apex", to_string(o.apex));
  w.put("vertices_mm", o.vertices_mm);
  w.put("distance_mm", o.distance_mm);
  w.put("reference", to_string(o.reference));
  w.put("lateral_offset_mm", o.lateral_offset_mm);
  if (o.corner_radius_mm != 0) w.put("corner_radius_mm", o.corner_radius_mm);
}

void write_protocol(TomlWriter& w, const ProtocolDef& p) {
  w.section("protocol");
  w.put("clog_breaking", to_string(p.clog_breaking));
  w.put("reinject_passed", p.reinject_passed);
  w.put("perturb_radius_d", p.perturb_radius_d);
}

void write_run(TomlWriter& w, const RunDef& r) {
  w.section("run");
  w.put("end", to_string(r.end));
  w.put("time_limit_s", r.time_limit_s);
  w.put("n_passed", r.n_passed);
  w.put("clog_timeout_s", r.clog_timeout_s);
  w.put("stop_after_no_flow_s", r.stop_after_no_flow_s);
  w.put("stranded_max", r.stranded_max);
  w.put("seed", r.seed);
  w.put("replicate", r.replicate);
}

void write_model(TomlWriter& w, const ModelDef& m) {
  w.section("model.box2d");
  w.put("time_step_s", m.box2d.time_step_s);
  w.put("velocity_iterations", m.box2d.velocity_iterations);
  w.put("position_iterations", m.box2d.position_iterations);
  w.put("sleeping", m.box2d.sleeping);
  w.put("continuous_collision", m.box2d.continuous_collision);
  w.put("engine_diameter", m.box2d.engine_diameter);
  if (m.box2d.rolling_contact != 0) w.put("rolling_contact", m.box2d.rolling_contact);
  // Written only when set, so that the hashes (job keys) of earlier scenarios stay what they were.
  if (m.box2d.spin_inertia_factor != Box2DDef{}.spin_inertia_factor)
    w.put("spin_inertia_factor", m.box2d.spin_inertia_factor);
  w.section("model.box2d.rolling");
  w.put("enabled", m.box2d.rolling.enabled);
  w.put("inertia_factor", m.box2d.rolling.inertia_factor);
  w.section("model.box2d.base_friction");
  w.put("enabled", m.box2d.base_friction.enabled);
  w.put("method", to_string(m.box2d.base_friction.method));
  w.section("model.bullet");
  w.put("time_step_s", m.bullet.time_step_s);
  w.put("substeps", m.bullet.substeps);
  w.put("solver_iterations", m.bullet.solver_iterations);
  w.put("sleeping", m.bullet.sleeping);
  w.put("engine_diameter", m.bullet.engine_diameter);
  w.put("wall_height_d", m.bullet.wall_height_d);
  w.put("collision_margin_d", m.bullet.collision_margin_d);
}

}  // namespace

std::string canonical_toml(const ScenarioDef& def) {
  TomlWriter w;
  write_head(w, def);
  write_particles(w, def.particles, def.release);
  write_obstruction(w, def.obstruction);
  write_shake(w, "shaking.walls", def.shaking.walls);
  write_shake(w, "shaking.obstruction", def.shaking.obstruction);
  write_protocol(w, def.protocol);
  write_run(w, def.run);
  write_model(w, def.model);
  return std::move(w).str();
}

std::uint64_t scenario_hash(const ScenarioDef& def) {
  std::uint64_t h = 0xcbf29ce484222325ull;  // FNV-1a 64 offset basis
  for (unsigned char c : canonical_toml(def)) {
    h ^= c;
    h *= 0x100000001b3ull;  // FNV-1a 64 prime
  }
  // FNV-1a mixes its last bytes poorly; one SplitMix64 round spreads them.
  return splitmix64(h);
}

}  // namespace gapflow

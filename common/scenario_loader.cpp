// Strict scenario loader: TOML text -> validated ScenarioDef (+ where each key was set).
//
// The file is parsed with toml++, command-line overrides are written into the
// parsed table, and only then is the table read section by section. Overrides
// therefore meet exactly the checks that the file meets. Every read registers
// its key as allowed, so a section's allowed-key list can never drift from what
// the reader actually understands.
#include "common/scenario_loader.hpp"

#include "common/input_bounds.hpp"
#include "common/scenario_section.hpp"
#include "common/text_file.hpp"
#include "common/toml_parse.hpp"
#include "common/toml_spelling.hpp"

#include <fmt/format.h>
#include <toml++/toml.h>

#include <algorithm>
#include <cmath>
#include <optional>
#include <utility>

namespace gapflow {

namespace {

std::string format_message(const SourceLocation& at, const std::string& key, const std::string& value,
                           const std::string& allowed) {
  std::string where = at.line > 0 ? fmt::format("{}:{}:{}", at.source, at.line, at.column) : at.source;
  if (key.empty()) return fmt::format("{}: {}", where, allowed);
  if (value.empty()) return fmt::format("{}: key '{}' is missing: {}", where, key, allowed);
  return fmt::format("{}: key '{}' = {}: {}", where, key, value, allowed);
}

}  // namespace

ScenarioError::ScenarioError(SourceLocation where, std::string key, std::string value, std::string allowed)
    : std::runtime_error(format_message(where, key, value, allowed)),
      where_(std::move(where)),
      key_(std::move(key)),
      value_(std::move(value)),
      allowed_(std::move(allowed)) {}

ScenarioInvalid::ScenarioInvalid(std::string key_, std::string value_, std::string allowed_)
    : std::runtime_error(fmt::format("key '{}' = {}: {}", key_, value_, allowed_)),
      key(std::move(key_)),
      value(std::move(value_)),
      allowed(std::move(allowed_)) {}

namespace {

using scenario_reading::Reader;
using scenario_reading::Section;
using scenario_reading::join_dotted;
using scenario_reading::value_text;

// ---------------------------------------------------------------- sections

void read_scenario_section(Section s, ScenarioDef& d) {
  const char* need = "required: a non-empty string";
  auto name = s.text("name");
  if (!name) s.missing("name", need);
  if (name->empty()) s.fail_value("name", "\"\"", need);
  d.name = *name;
  if (auto desc = s.text("description")) d.description = *desc;
  s.finish();
}

void read_plane(Section s, PlaneDef& p) {
  // Up to a vertical silo (90); whether spheres still roll there is checked when compiling.
  s.number("incline_deg", p.incline_deg, closed(0, 90, "deg"));
  s.number("length_mm", p.length_mm, lower_open(0, kMaxLengthMm, "mm"));
  s.number("width_mm", p.width_mm, lower_open(0, kMaxLengthMm, "mm"));
  s.number("lateral_tilt_deg", p.lateral_tilt_deg, closed(-10, 10, "deg"));
  s.number("cover_gap_mm", p.cover_gap_mm, closed(0, kMaxLengthMm, "mm"));
  s.finish();
}

void read_bottleneck(Section s, BottleneckDef& b) {
  s.number("wall_angle_deg", b.wall_angle_deg, closed(1, 90, "deg"));
  s.number("gap_mm", b.gap_mm, lower_open(0, kMaxLengthMm, "mm"));
  s.number("wall_thickness_mm", b.wall_thickness_mm, lower_open(0, kMaxLengthMm, "mm"));
  s.number("gap_offset_mm", b.gap_offset_mm, closed(-kMaxLengthMm, kMaxLengthMm, "mm"));
  s.finish();
  // W + delta < plane.width_mm is checked by compile_scenario (it needs the plane).
  if (b.gap_mm + b.gap_offset_mm <= 0)
    s.fail_value("gap_offset_mm", toml_double(b.gap_offset_mm),
                 fmt::format("must be > -bottleneck.gap_mm ({}): the effective gap W + delta must stay > 0 (mm)",
                             toml_double(b.gap_mm)));
}

// A number of mm, or one of the glass-bead presets of the paper.
void read_diameter(Section& s, double& out) {
  const toml::node* n = s.get("diameter_mm");
  if (!n) return;
  const Range range = closed(kMinDiameterMm, kMaxDiameterMm, "mm");
  const std::string allowed = "must be a number " + range.text() + " or one of: small, medium, large";
  if (auto str = n->as_string()) {
    const std::string& v = str->get();
    if (v == "small") out = 6.15;
    else if (v == "medium") out = 7.75;
    else if (v == "large") out = 11.9;
    else s.fail("diameter_mm", *n, allowed);
    return;
  }
  if (!n->is_number()) s.fail("diameter_mm", *n, allowed);
  const double v = *number_value(*n);
  if (!std::isfinite(v) || !range.contains(v)) s.fail("diameter_mm", *n, allowed);
  out = v;
}

void read_particles(Section s, ParticlesDef& p) {
  s.integer("count", p.count, 1, 1000000);
  read_diameter(s, p.diameter_mm);
  s.number("size_scatter", p.size_scatter, closed(0, 0.2));
  if (auto v = s.choice<SizeDistribution>("size_distribution", {{"none", SizeDistribution::none},
                                                                {"uniform", SizeDistribution::uniform},
                                                                {"normal", SizeDistribution::normal}}))
    p.size_distribution = *v;
  s.number("density_kg_m3", p.density_kg_m3, lower_open(0, 100000, "kg/m^3"));
  s.number("friction_particle", p.friction_particle, closed(0, 2));
  s.number("friction_wall", p.friction_wall, closed(0, 2));
  s.number("friction_base", p.friction_base, closed(0, 2));
  s.number("restitution", p.restitution, closed(0, 1));
  s.number("rolling_resistance", p.rolling_resistance, upper_open(0, 1));
  s.number("spinning_friction_mm", p.spinning_friction_mm, closed(0, kMaxDiameterMm, "mm"));
  s.number("drag_per_s", p.drag_per_s, closed(0, 100, "1/s"));
  s.number("quadratic_drag_per_m", p.quadratic_drag_per_m, closed(0, 100, "1/m"));
  s.finish();
}

void read_release(Section s, ReleaseDef& r) {
  s.number("barrier_mm", r.barrier_mm, closed(0, kMaxLengthMm, "mm"));
  s.number("settle_s", r.settle_s, closed(0, 60, "s"));
  s.number("lattice_gap", r.lattice_gap, closed(0, 1));
  s.finish();
}

// ---- obstruction

double cross(Vec2 o, Vec2 a, Vec2 b) { return (a.x - o.x) * (b.y - o.y) - (a.y - o.y) * (b.x - o.x); }

double signed_area(const std::vector<Vec2>& p) {
  double a = 0;
  for (std::size_t i = 0; i < p.size(); ++i) {
    const Vec2& u = p[i];
    const Vec2& v = p[(i + 1) % p.size()];
    a += u.x * v.y - v.x * u.y;
  }
  return 0.5 * a;
}

// Counter-clockwise and strictly convex: every other vertex lies strictly left of
// every edge. (Checking only consecutive turns would accept a pentagram.)
bool strictly_convex_ccw(const std::vector<Vec2>& p, double eps) {
  const std::size_t n = p.size();
  for (std::size_t i = 0; i < n; ++i)
    for (std::size_t j = 0; j < n; ++j)
      if (j != i && j != (i + 1) % n && cross(p[i], p[(i + 1) % n], p[j]) <= eps) return false;
  return true;
}

// The smallest obstruction feature (edge, width, diameter) the engines can build:
// Box2D welds polygon vertices closer than half its linear slop and asserts on a
// degenerate hull, so a shape far smaller than a particle is refused here with the reason.
double min_feature_mm(double particle_d_mm) { return particle_d_mm / (1 / kMinFeatureD); }  // d / 10, printed short

std::vector<Vec2> read_vertices(Section& s, double particle_d_mm) {
  constexpr int kMaxVertices = 8;  // b2_maxPolygonVertices (Box2D 2.4)
  const double min_mm = min_feature_mm(particle_d_mm);
  const std::string allowed = fmt::format(
      "must be an array of 3 to {} [x, y] number pairs (mm, each |coordinate| <= {}) forming a strictly convex "
      "polygon whose edges and widths are all >= {} d = {} mm",
      kMaxVertices, kMaxLengthMm, kMinFeatureD, min_mm);
  const toml::node* n = s.get("vertices_mm");
  if (!n) s.missing("vertices_mm", "required for shape = \"polygon\": " + allowed.substr(8));
  const toml::array* a = n->as_array();
  if (!a) s.fail("vertices_mm", *n, allowed);
  if (a->size() < 3 || a->size() > kMaxVertices) s.fail("vertices_mm", *n, allowed);
  std::vector<Vec2> pts;
  for (const toml::node& e : *a) {
    const toml::array* xy = e.as_array();
    if (!xy || xy->size() != 2 || !(*xy)[0].is_number() || !(*xy)[1].is_number())
      s.fail("vertices_mm", *n, allowed);
    Vec2 v{*number_value((*xy)[0]), *number_value((*xy)[1])};
    if (!(std::abs(v.x) <= kMaxLengthMm) || !(std::abs(v.y) <= kMaxLengthMm)) s.fail("vertices_mm", *n, allowed);
    pts.push_back(v);
  }
  double scale = 0;
  for (const Vec2& v : pts) scale = std::max({scale, std::abs(v.x), std::abs(v.y)});
  const double eps = 1e-12 * scale * scale;
  double area = signed_area(pts);
  if (std::abs(area) <= eps) s.fail("vertices_mm", *n, allowed);
  if (area < 0) std::reverse(pts.begin(), pts.end());  // accept clockwise input
  if (!strictly_convex_ccw(pts, eps)) s.fail("vertices_mm", *n, allowed);
  // Every edge long enough, and every other vertex far enough from each edge's line.
  const std::size_t m = pts.size();
  for (std::size_t i = 0; i < m; ++i) {
    const Vec2 p = pts[i], q = pts[(i + 1) % m];
    const double edge = std::hypot(q.x - p.x, q.y - p.y);
    if (edge < min_mm)
      s.fail("vertices_mm", *n, fmt::format("{} (edge {} is {:.4g} mm)", allowed, i + 1, edge));
    for (std::size_t j = 0; j < m; ++j)
      if (j != i && j != (i + 1) % m && cross(p, q, pts[j]) / edge < min_mm)
        s.fail("vertices_mm", *n, fmt::format("{} (too thin: vertex {} is {:.4g} mm from edge {})", allowed, j + 1,
                                              cross(p, q, pts[j]) / edge, i + 1));
  }
  return pts;
}

enum class ShapeChoice { none, cylinder, triangle, polygon, A, V };

void apply_shape(ShapeChoice c, ObstructionDef& o) {
  switch (c) {
    case ShapeChoice::none: o.shape = ObstructionShape::none; break;
    case ShapeChoice::cylinder: o.shape = ObstructionShape::cylinder; break;
    case ShapeChoice::triangle: o.shape = ObstructionShape::triangle; break;
    case ShapeChoice::polygon: o.shape = ObstructionShape::polygon; break;
    case ShapeChoice::A: o.shape = ObstructionShape::triangle; o.preset = "A"; o.apex = Apex::away_from_gap; break;
    case ShapeChoice::V: o.shape = ObstructionShape::triangle; o.preset = "V"; o.apex = Apex::toward_gap; break;
  }
}

void read_triangle(Section& s, ObstructionDef& o, double particle_d_mm) {
  s.number("side_mm", o.side_mm, closed(min_feature_mm(particle_d_mm), kMaxLengthMm, "mm; at least 0.1 d"));
  const toml::node* n = s.get("apex");
  if (!n) return;
  const char* names = "one of: away_from_gap, toward_gap";
  if (!n->is_string()) s.fail("apex", *n, std::string("must be a string, ") + names);
  const std::string& v = n->as_string()->get();
  if (v != "away_from_gap" && v != "toward_gap") s.fail("apex", *n, names);
  Apex apex = v == "toward_gap" ? Apex::toward_gap : Apex::away_from_gap;
  if (!o.preset.empty() && apex != o.apex)
    s.fail("apex", *n, fmt::format("must be \"{}\" for shape = \"{}\" (or omit apex)", to_string(o.apex), o.preset));
  o.apex = apex;
}

void read_obstruction(Section s, ObstructionDef& o, double particle_d_mm) {
  auto shape = s.choice<ShapeChoice>("shape", {{"none", ShapeChoice::none},
                                               {"cylinder", ShapeChoice::cylinder},
                                               {"triangle", ShapeChoice::triangle},
                                               {"polygon", ShapeChoice::polygon},
                                               {"A", ShapeChoice::A},
                                               {"V", ShapeChoice::V}});
  if (shape) apply_shape(*shape, o);
  // Keys of other shapes are ignored so that `--set obstruction.shape=...` works on any file.
  const Range size = closed(min_feature_mm(particle_d_mm), kMaxLengthMm, "mm; at least 0.1 d");
  if (o.shape == ObstructionShape::cylinder) s.number("diameter_mm", o.diameter_mm, size);
  else s.ignore("diameter_mm");
  if (o.shape == ObstructionShape::triangle) read_triangle(s, o, particle_d_mm);
  else { s.ignore("side_mm"); s.ignore("apex"); }
  if (o.shape == ObstructionShape::polygon) o.vertices_mm = read_vertices(s, particle_d_mm);
  else s.ignore("vertices_mm");
  s.number("distance_mm", o.distance_mm, closed(0, kMaxLengthMm, "mm"));
  if (auto r = s.choice<DistanceReference>("reference", {{"nearest", DistanceReference::nearest},
                                                         {"centre", DistanceReference::centre},
                                                         {"center", DistanceReference::centre}}))
    o.reference = *r;
  s.number("lateral_offset_mm", o.lateral_offset_mm, closed(-kMaxLengthMm, kMaxLengthMm, "mm"));
  // Below the shape's inradius: checked by compile_scenario, which builds the outline.
  s.number("corner_radius_mm", o.corner_radius_mm, closed(0, kMaxLengthMm, "mm"));
  s.finish();
  if (o.corner_radius_mm > 0 && o.shape != ObstructionShape::triangle && o.shape != ObstructionShape::polygon)
    s.fail_value("corner_radius_mm", toml_double(o.corner_radius_mm),
                 fmt::format("must be 0 for shape = \"{}\": only triangle and polygon corners can be rounded",
                             to_string(o.shape)));
}

void read_shake(Section s, ShakeDef& k) {
  s.boolean("enabled", k.enabled);
  s.number("amplitude_mm", k.amplitude_mm, closed(0, kMaxAmplitudeMm, "mm"));
  s.number("direction_deg", k.direction_deg, closed(-360, 360, "deg"));
  s.boolean("mirror", k.mirror);
  s.number("decay_s", k.decay_s, lower_open(0, kMaxTimeS, "s"));
  s.number("period_s", k.period_s, lower_open(0, kMaxTimeS, "s"));
  s.number("start_s", k.start_s, closed(0, kMaxTimeS, "s"));
  s.number("frequency_hz", k.frequency_hz, lower_open(0, kMaxFrequencyHz, "Hz"));
  s.finish();
  if (k.decay_s > k.period_s)
    s.fail_value("decay_s", toml_double(k.decay_s),
                 fmt::format("must be <= {}.period_s ({})", s.path(), toml_double(k.period_s)), "period_s");
}

void read_shaking(Section s, ShakingDef& k) {
  Section walls = s.section("walls");
  Section obstruction = s.section("obstruction");
  s.finish();
  read_shake(walls, k.walls);
  read_shake(obstruction, k.obstruction);
}

void read_run(Section s, RunDef& r, int particle_count) {
  if (auto e = s.choice<EndCondition>("end", {{"all_passed", EndCondition::all_passed},
                                              {"time_limit", EndCondition::time_limit},
                                              {"n_passed", EndCondition::n_passed}}))
    r.end = *e;
  s.number("time_limit_s", r.time_limit_s, lower_open(0, kMaxTimeS, "s"));
  // 0 is the "unused" default, so that canonical_toml of any end condition reads back.
  s.integer("n_passed", r.n_passed, 0);
  s.number("clog_timeout_s", r.clog_timeout_s, lower_open(0, kMaxTimeS, "s"));
  s.number("stop_after_no_flow_s", r.stop_after_no_flow_s, closed(0, kMaxTimeS, "s"));
  s.integer("stranded_max", r.stranded_max, 0, 1000000);
  if (auto seed = s.integer_value("seed", 0)) r.seed = static_cast<std::uint64_t>(*seed);
  s.integer("replicate", r.replicate, 0, 1000000000);
  s.finish();

  if (r.end == EndCondition::n_passed) {
    std::string need = fmt::format("required when run.end = \"n_passed\": an integer in [1, {}] (particles.count)",
                                   particle_count);
    if (!s.set("n_passed")) s.missing("n_passed", need, s.location("end"));
    if (r.n_passed < 1 || r.n_passed > particle_count) s.fail_value("n_passed", std::to_string(r.n_passed), need);
  }
  if (r.stop_after_no_flow_s > 0 && r.stop_after_no_flow_s < r.clog_timeout_s)
    s.fail_value("stop_after_no_flow_s", toml_double(r.stop_after_no_flow_s),
                 fmt::format("must be 0 (never) or >= run.clog_timeout_s ({})", toml_double(r.clog_timeout_s)),
                 "clog_timeout_s");
}

void read_protocol(Section s, ProtocolDef& p) {
  if (auto c = s.choice<ClogBreaking>("clog_breaking", {{"shaking", ClogBreaking::shaking},
                                                        {"local_perturbation", ClogBreaking::local_perturbation},
                                                        {"refill", ClogBreaking::refill}}))
    p.clog_breaking = *c;
  s.boolean("reinject_passed", p.reinject_passed);
  s.number("perturb_radius_d", p.perturb_radius_d, closed(0.5, 50));
  s.finish();
}

void read_box2d(Section s, Box2DDef& b) {
  s.number("time_step_s", b.time_step_s, closed(kMinTimeStepS, kMaxTimeStepS, "s"));
  s.integer("velocity_iterations", b.velocity_iterations, 1, 1000);
  s.integer("position_iterations", b.position_iterations, 0, 1000);
  s.boolean("sleeping", b.sleeping);
  s.boolean("continuous_collision", b.continuous_collision);
  s.number("engine_diameter", b.engine_diameter, closed(0.05, 20));
  s.number("rolling_contact", b.rolling_contact, closed(0, 1, "fraction of the derived force"));
  s.number("spin_inertia_factor", b.spin_inertia_factor, lower_open(0, 1));
  Section rolling = s.section("rolling");
  Section base = s.section("base_friction");
  s.finish();

  rolling.boolean("enabled", b.rolling.enabled);
  rolling.number("inertia_factor", b.rolling.inertia_factor, lower_open(0, 1));
  rolling.finish();
  // The effect's force law assumes spheres rolling without slipping on the board.
  if (b.rolling_contact > 0 && !b.rolling.enabled)
    s.fail_value("rolling_contact", toml_double(b.rolling_contact),
                 "must be 0 when model.box2d.rolling.enabled = false (the effect acts through the rolling spin)");
  // A rolling sphere's inertia is the rolling effect's: a second value would contradict it.
  if (b.rolling.enabled && b.spin_inertia_factor != Box2DDef{}.spin_inertia_factor)
    s.fail_value("spin_inertia_factor", toml_double(b.spin_inertia_factor),
                 "applies only with model.box2d.rolling.enabled = false (rolling spheres use rolling.inertia_factor)");

  base.boolean("enabled", b.base_friction.enabled);
  if (auto m = base.choice<BaseFrictionMethod>("method", {{"force", BaseFrictionMethod::force},
                                                          {"joint", BaseFrictionMethod::joint}}))
    b.base_friction.method = *m;
  base.finish();
}

void read_bullet(Section s, BulletDef& b) {
  s.number("time_step_s", b.time_step_s, closed(kMinTimeStepS, kMaxTimeStepS, "s"));
  s.integer("substeps", b.substeps, 1, 100);
  s.integer("solver_iterations", b.solver_iterations, 1, 1000);
  s.boolean("sleeping", b.sleeping);
  s.number("engine_diameter", b.engine_diameter, closed(0.05, 20));
  s.number("wall_height_d", b.wall_height_d, closed(1.5, 100));
  s.number("collision_margin_d", b.collision_margin_d, closed(0, 0.5));
  s.finish();
}

void read_model(Section s, ModelDef& m) {
  Section box2d = s.section("box2d");
  Section bullet = s.section("bullet");
  s.finish();
  read_box2d(box2d, m.box2d);
  read_bullet(bullet, m.bullet);
}

ScenarioDef read_document(Reader& r, const toml::table& doc) {
  Section root(r, &doc, "");
  // All sections are taken first so that a misspelt section is reported before its contents matter.
  Section scenario = root.section("scenario"), plane = root.section("plane"),
          bottleneck = root.section("bottleneck"), particles = root.section("particles"),
          release = root.section("release"), obstruction = root.section("obstruction"),
          shaking = root.section("shaking"), protocol = root.section("protocol"), run = root.section("run"),
          model = root.section("model");
  root.finish();

  ScenarioDef d;
  read_scenario_section(scenario, d);
  read_plane(plane, d.plane);
  read_bottleneck(bottleneck, d.bottleneck);
  read_particles(particles, d.particles);
  read_release(release, d.release);
  read_obstruction(obstruction, d.obstruction, d.particles.diameter_mm);
  read_shaking(shaking, d.shaking);
  read_protocol(protocol, d.protocol);
  read_run(run, d.run, d.particles.count);
  read_model(model, d.model);
  if (d.protocol.reinject_passed && d.run.end == EndCondition::all_passed)
    run.fail_value("end", "\"all_passed\"",
                   "with protocol.reinject_passed = true the board never empties: use \"time_limit\" or \"n_passed\"");
  return d;
}

// ---------------------------------------------------------------- overrides

std::string trim(std::string_view s) {
  auto b = s.find_first_not_of(" \t");
  if (b == std::string_view::npos) return {};
  auto e = s.find_last_not_of(" \t");
  return std::string(s.substr(b, e - b + 1));
}

std::vector<std::string> split_key(const std::string& key) {
  std::vector<std::string> parts;
  std::size_t start = 0;
  for (;;) {
    auto dot = key.find('.', start);
    parts.push_back(key.substr(start, dot - start));
    if (dot == std::string::npos) return parts;
    start = dot + 1;
  }
}

bool is_bare_key(const std::string& part) {
  return !part.empty() && std::all_of(part.begin(), part.end(), [](unsigned char c) {
    return std::isalnum(c) || c == '_' || c == '-';
  });
}

// The override value as TOML; anything that is not one TOML value is a bare string.
toml::table parse_override_value(const std::string& value) {
  try {
    toml::table t = toml::parse("v = " + value);
    if (t.size() == 1 && t.contains("v")) return t;
  } catch (const toml::parse_error&) {
  }
  toml::table t;
  t.insert("v", value);
  return t;
}

void apply_override(toml::table& doc, const std::string& text, int index, Reader& r) {
  auto eq = text.find('=');
  if (eq == std::string::npos)
    throw ScenarioError({"--set", index, 1}, "", "",
                        fmt::format("override '{}' must have the form key=value", text));
  std::string key = trim(std::string_view(text).substr(0, eq));
  std::string_view rest = std::string_view(text).substr(eq + 1);
  auto lead = std::min(rest.find_first_not_of(" \t"), rest.size());
  SourceLocation at{"--set", index, static_cast<int>(eq + 2 + lead)};
  std::vector<std::string> parts = split_key(key);
  if (!std::all_of(parts.begin(), parts.end(), is_bare_key))
    throw ScenarioError({"--set", index, 1}, key, trim(rest),
                        "the key must be dotted, e.g. obstruction.distance_mm");

  toml::table* t = &doc;
  std::string path;
  for (std::size_t i = 0; i + 1 < parts.size(); ++i) {
    path = join_dotted(path, parts[i]);
    if (!t->contains(parts[i])) {
      t->insert(parts[i], toml::table{});
      r.overridden[path] = at;
    }
    toml::node* n = t->get(parts[i]);
    if (!n->is_table())
      throw ScenarioError(at, path, value_text(*n),
                          fmt::format("must be a table (section [{}]) to set '{}'", path, key));
    t = n->as_table();
  }
  toml::table value = parse_override_value(trim(rest));
  t->insert_or_assign(parts.back(), *value.get("v"));
  r.overridden[key] = at;
}

LoadedScenario parse_with(std::string_view text, std::string source, const std::vector<std::string>& overrides) {
  Reader r;
  r.source = source;
  toml::table doc = parse_toml_located(text, source);
  for (std::size_t i = 0; i < overrides.size(); ++i) apply_override(doc, overrides[i], static_cast<int>(i + 1), r);
  LoadedScenario out;
  out.def = read_document(r, doc);
  out.where = std::move(r.where);
  out.source = std::move(source);
  return out;
}

}  // namespace

LoadedScenario parse_scenario(std::string_view text, std::string_view source_name,
                              const std::vector<std::string>& overrides) {
  return parse_with(text, std::string(source_name), overrides);
}

LoadedScenario load_scenario(const std::filesystem::path& file, const std::vector<std::string>& overrides) {
  std::string text;
  try {
    text = read_input_file(file, "scenario file");
  } catch (const FileError& e) {
    throw ScenarioError({file.string(), 0, 0}, "", "", e.reason());
  }
  return parse_with(text, file.string(), overrides);
}

ScenarioError locate(const ScenarioInvalid& e, const LoadedScenario& s) {
  if (auto it = s.where.find(e.key); it != s.where.end()) return ScenarioError(it->second, e.key, e.value, e.allowed);
  // Not set anywhere: the value is a default; point at the nearest enclosing section.
  std::string value = e.value.empty() ? e.value : e.value + " (default)";
  for (std::string k = e.key; !k.empty();) {
    auto dot = k.rfind('.');
    k = dot == std::string::npos ? std::string() : k.substr(0, dot);
    if (auto it = s.where.find(k); !k.empty() && it != s.where.end())
      return ScenarioError(it->second, e.key, value, e.allowed);
  }
  return ScenarioError({s.source, 1, 1}, e.key, value, e.allowed);
}

}  // namespace gapflow

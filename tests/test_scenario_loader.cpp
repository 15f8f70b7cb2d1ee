// Scenario loader: strict validation with located errors, overrides, presets,
// canonical text and hash, and the shipped scenario files.
#include "tests/test_support.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <optional>
#include <string>
#include <vector>

using gapflow::LoadedScenario;
using gapflow::ScenarioDef;
using gapflow::ScenarioError;
using gapflow::ScenarioInvalid;

namespace {

// Lines 1-2 of most test documents.
const std::string kHead = "[scenario]\nname = \"t\"\n";

std::optional<ScenarioError> error_of(const std::string& text, const std::vector<std::string>& overrides = {}) {
  try {
    gapflow::parse_scenario(text, "test.toml", overrides);
  } catch (const ScenarioError& e) {
    return e;
  }
  return std::nullopt;
}

// ------------------------------------------------------------------ malformed scenarios

struct BadCase {
  const char* name;
  std::string text;
  std::string key;     // expected ScenarioError::key()
  int line;            // expected line
  std::vector<std::string> overrides = {};
  std::string source = "test.toml";
};

std::ostream& operator<<(std::ostream& os, const BadCase& c) { return os << c.name; }

class Malformed : public ::testing::TestWithParam<BadCase> {};

TEST_P(Malformed, IsRejectedWithKeyAndLine) {
  const BadCase& c = GetParam();
  auto e = error_of(c.text, c.overrides);
  ASSERT_TRUE(e.has_value()) << "accepted:\n" << c.text;
  EXPECT_EQ(e->key(), c.key) << e->what();
  EXPECT_EQ(e->where().line, c.line) << e->what();
  EXPECT_EQ(e->where().source, c.source) << e->what();
  // One line, starting with the location.
  std::string what = e->what();
  EXPECT_EQ(what.find('\n'), std::string::npos) << what;
  EXPECT_EQ(what.rfind(c.source + ":" + std::to_string(c.line) + ":", 0), 0u) << what;
  if (!c.key.empty()) {
    EXPECT_NE(what.find("key '" + c.key + "'"), std::string::npos) << what;
  }
}

const BadCase kBadCases[] = {
    {"wrong_type", kHead + "[plane]\nwidth_mm = \"wide\"\n", "plane.width_mm", 4},
    {"unknown_key", kHead + "[bottleneck]\ngap = 30\n", "bottleneck.gap", 4},
    {"unknown_section", kHead + "[obstacle]\nshape = \"cylinder\"\n", "obstacle", 3},
    {"unknown_top_level_key", "title = \"x\"\n" + kHead, "title", 1},
    {"negative_gap", kHead + "[bottleneck]\nwall_angle_deg = 30\ngap_mm = -3\n", "bottleneck.gap_mm", 5},
    {"zero_count", kHead + "[particles]\ncount = 0\n", "particles.count", 4},
    {"float_count", kHead + "[particles]\ncount = 100.0\n", "particles.count", 4},
    {"bad_preset", kHead + "[particles]\ndiameter_mm = \"huge\"\n", "particles.diameter_mm", 4},
    {"zero_diameter", kHead + "[particles]\ndiameter_mm = 0\n", "particles.diameter_mm", 4},
    {"bad_distribution", kHead + "[particles]\nsize_distribution = \"lognormal\"\n",
     "particles.size_distribution", 4},
    {"restitution_above_1", kHead + "[particles]\nrestitution = 1.5\n", "particles.restitution", 4},
    {"size_scatter_too_large", kHead + "[particles]\nsize_scatter = 0.3\n", "particles.size_scatter", 4},
    {"negative_friction", kHead + "[particles]\nfriction_wall = -0.1\n", "particles.friction_wall", 4},
    {"rolling_resistance_1", kHead + "[particles]\nrolling_resistance = 1.0\n", "particles.rolling_resistance", 4},
    {"nan", kHead + "[plane]\nincline_deg = nan\n", "plane.incline_deg", 4},
    {"inf", kHead + "[plane]\nlength_mm = inf\n", "plane.length_mm", 4},
    {"incline_91", kHead + "[plane]\nincline_deg = 91\n", "plane.incline_deg", 4},
    {"spin_inertia_with_rolling", kHead + "[model.box2d]\nspin_inertia_factor = 0.5\n", "model.box2d.spin_inertia_factor", 4},
    {"wall_angle_0", kHead + "[bottleneck]\nwall_angle_deg = 0\n", "bottleneck.wall_angle_deg", 4},
    {"lattice_gap_2", kHead + "[release]\nlattice_gap = 2\n", "release.lattice_gap", 4},
    {"settle_61", kHead + "[release]\nsettle_s = 61\n", "release.settle_s", 4},
    {"decay_above_period", kHead + "[shaking.walls]\nenabled = true\ndecay_s = 6.0\nperiod_s = 5.0\n",
     "shaking.walls.decay_s", 5},
    {"default_decay_above_period", kHead + "[shaking.obstruction]\nperiod_s = 0.5\n",
     "shaking.obstruction.decay_s", 4},
    {"shaking_subsection_scalar", kHead + "[shaking]\nwalls = true\n", "shaking.walls", 4},
    {"n_passed_missing", kHead + "[run]\nend = \"n_passed\"\n", "run.n_passed", 4},
    {"n_passed_too_large", kHead + "[particles]\ncount = 10\n[run]\nend = \"n_passed\"\nn_passed = 11\n",
     "run.n_passed", 7},
    {"stop_before_clog", kHead + "[run]\nclog_timeout_s = 2.0\nstop_after_no_flow_s = 1.0\n",
     "run.stop_after_no_flow_s", 5},
    {"stranded_negative", kHead + "[run]\nstranded_max = -1\n", "run.stranded_max", 4},
    {"float_seed", kHead + "[run]\nseed = 1.5\n", "run.seed", 4},
    {"negative_seed", kHead + "[run]\nseed = -1\n", "run.seed", 4},
    {"bad_end", kHead + "[run]\nend = \"never\"\n", "run.end", 4},
    {"vertices_not_convex",
     kHead + "[obstruction]\nshape = \"polygon\"\nvertices_mm = [[0, 0], [10, 0], [2, 2], [0, 10]]\n",
     "obstruction.vertices_mm", 5},
    {"vertices_star",
     kHead + "[obstruction]\nshape = \"polygon\"\n"
             "vertices_mm = [[0, 10], [6, -8], [-9.5, 3], [9.5, 3], [-6, -8]]\n",
     "obstruction.vertices_mm", 5},
    {"two_vertices", kHead + "[obstruction]\nshape = \"polygon\"\nvertices_mm = [[0, 0], [10, 0]]\n",
     "obstruction.vertices_mm", 5},
    {"vertices_collinear",
     kHead + "[obstruction]\nshape = \"polygon\"\nvertices_mm = [[0, 0], [1, 1], [2, 2]]\n",
     "obstruction.vertices_mm", 5},
    {"vertex_not_a_pair", kHead + "[obstruction]\nshape = \"polygon\"\nvertices_mm = [[0, 0], [10, 0], [5]]\n",
     "obstruction.vertices_mm", 5},
    {"polygon_without_vertices", kHead + "[obstruction]\nshape = \"polygon\"\n", "obstruction.vertices_mm", 3},
    {"A_with_apex_toward_gap", kHead + "[obstruction]\nshape = \"A\"\nside_mm = 20\napex = \"toward_gap\"\n",
     "obstruction.apex", 6},
    {"V_with_apex_away", kHead + "[obstruction]\napex = \"away_from_gap\"\nshape = \"V\"\n", "obstruction.apex", 4},
    {"bad_shape", kHead + "[obstruction]\nshape = \"circle\"\n", "obstruction.shape", 4},
    {"bad_reference", kHead + "[obstruction]\nreference = \"middle\"\n", "obstruction.reference", 4},
    {"negative_distance", kHead + "[obstruction]\ndistance_mm = -3\n", "obstruction.distance_mm", 4},
    {"empty_file", "", "scenario.name", 1},
    {"empty_name", "[scenario]\nname = \"\"\n", "scenario.name", 2},
    {"name_not_string", "[scenario]\n\nname = 42\n", "scenario.name", 3},
    {"syntax_error", kHead + "[plane]\nwidth_mm = = 3\n", "", 4},
    {"duplicate_key", kHead + "[plane]\nwidth_mm = 3\nwidth_mm = 4\n", "", 5},
    {"section_as_scalar", "plane = 5\n" + kHead, "plane", 1},
    {"time_step_0", kHead + "[model.box2d]\ntime_step_s = 0\n", "model.box2d.time_step_s", 4},
    {"velocity_iterations_0", kHead + "[model.box2d]\nvelocity_iterations = 0\n",
     "model.box2d.velocity_iterations", 4},
    {"inertia_factor_0", kHead + "[model.box2d.rolling]\ninertia_factor = 0\n",
     "model.box2d.rolling.inertia_factor", 4},
    {"unknown_nested_key", kHead + "[model.box2d.rolling]\nenable = true\n", "model.box2d.rolling.enable", 4},
    {"bad_friction_method", kHead + "[model.box2d.base_friction]\nmethod = \"magic\"\n",
     "model.box2d.base_friction.method", 4},
    {"engine_diameter_100", kHead + "[model.bullet]\nengine_diameter = 100\n", "model.bullet.engine_diameter", 4},
    {"wall_height_1", kHead + "[model.bullet]\nwall_height_d = 1.0\n", "model.bullet.wall_height_d", 4},
    {"bool_as_string", kHead + "[model.bullet]\nsleeping = \"no\"\n", "model.bullet.sleeping", 4},
    {"substeps_float", kHead + "[model.bullet]\nsubsteps = 2.0\n", "model.bullet.substeps", 4},
    {"set_unknown_key", kHead, "obstruction.radius_mm", 1, {"obstruction.radius_mm=3"}, "--set"},
    {"set_unknown_section", kHead, "wind", 2, {"plane.width_mm=300", "wind.speed=3"}, "--set"},
    {"set_bad_value_type", kHead, "particles.count", 2, {"plane.width_mm=300", "particles.count=12.5"}, "--set"},
    {"set_bare_string_for_number", kHead, "bottleneck.gap_mm", 1, {"bottleneck.gap_mm=wide"}, "--set"},
    {"set_without_equals", kHead, "", 1, {"plane.width_mm"}, "--set"},
    {"set_through_scalar", kHead, "scenario.name", 1, {"scenario.name.first=1"}, "--set"},
    {"set_bad_range", kHead + "[bottleneck]\ngap_mm = 30\n", "bottleneck.gap_mm", 1, {"bottleneck.gap_mm=-1"},
     "--set"},
};

INSTANTIATE_TEST_SUITE_P(Loader, Malformed, ::testing::ValuesIn(kBadCases),
                         [](const ::testing::TestParamInfo<BadCase>& info) { return std::string(info.param.name); });

// ------------------------------------------------------------------ error messages

TEST(ScenarioLoader, ErrorMessageNamesFileLineKeyValueAndRule) {
  auto e = error_of(kHead + "[bottleneck]\ngap_mm = -3\n");
  ASSERT_TRUE(e);
  EXPECT_EQ(e->value(), "-3");
  EXPECT_EQ(std::string(e->what()), "test.toml:4:" + std::to_string(e->where().column) +
                                        ": key 'bottleneck.gap_mm' = -3: must be in (0, 100000] (mm)");
}

TEST(ScenarioLoader, UnknownKeyListsTheAllowedKeys) {
  auto e = error_of(kHead + "[plane]\nwidht_mm = 300\n");
  ASSERT_TRUE(e);
  EXPECT_NE(e->allowed().find("incline_deg, length_mm, width_mm"), std::string::npos) << e->what();
}

TEST(ScenarioLoader, ChoiceErrorListsTheChoices) {
  auto e = error_of(kHead + "[obstruction]\nshape = \"circle\"\n");
  ASSERT_TRUE(e);
  EXPECT_EQ(e->value(), "\"circle\"");
  EXPECT_EQ(e->allowed(), "one of: none, cylinder, triangle, polygon, A, V");
}

TEST(ScenarioLoader, MissingNameMessage) {
  auto e = error_of("");
  ASSERT_TRUE(e);
  EXPECT_EQ(std::string(e->what()).rfind("test.toml:1:1: key 'scenario.name' is missing: ", 0), 0u) << e->what();
}

TEST(ScenarioLoader, SyntaxErrorCarriesTomlPosition) {
  auto e = error_of("[scenario]\nname = \"t\"\n[plane\n");
  ASSERT_TRUE(e);
  EXPECT_EQ(e->key(), "");
  EXPECT_EQ(e->where().line, 3);
  EXPECT_GT(e->where().column, 1);
  EXPECT_FALSE(e->allowed().empty());
}

// ------------------------------------------------------------------ accepted scenarios

TEST(ScenarioLoader, MinimalFileGivesDefaults) {
  LoadedScenario s = gapflow::parse_scenario(kHead, "min.toml");
  EXPECT_EQ(s.def.name, "t");
  EXPECT_EQ(s.source, "min.toml");
  EXPECT_EQ(s.def.particles.count, 1551);
  EXPECT_DOUBLE_EQ(s.def.bottleneck.gap_mm, 33.0);
  EXPECT_EQ(s.def.obstruction.shape, gapflow::ObstructionShape::none);
  ASSERT_TRUE(s.where.count("scenario.name"));
  EXPECT_EQ(s.where.at("scenario.name").line, 2);
  EXPECT_EQ(s.where.count("plane.width_mm"), 0u);
}

TEST(ScenarioLoader, IntegerAcceptedWhereFloatExpected) {
  auto s = gapflow::parse_scenario(kHead + "[bottleneck]\ngap_mm = 40\n", "t.toml");
  EXPECT_DOUBLE_EQ(s.def.bottleneck.gap_mm, 40.0);
  EXPECT_EQ(s.where.at("bottleneck.gap_mm").line, 4);
  EXPECT_EQ(s.where.at("bottleneck").line, 3);
}

TEST(ScenarioLoader, DiameterPresetsResolve) {
  auto diameter = [](const char* preset) {
    return gapflow::parse_scenario(kHead + "[particles]\ndiameter_mm = \"" + preset + "\"\n", "t.toml")
        .def.particles.diameter_mm;
  };
  EXPECT_DOUBLE_EQ(diameter("small"), 6.15);
  EXPECT_DOUBLE_EQ(diameter("medium"), 7.75);
  EXPECT_DOUBLE_EQ(diameter("large"), 11.9);
}

TEST(ScenarioLoader, TrianglePresetsSetApex) {
  auto a = gapflow::parse_scenario(kHead + "[obstruction]\nshape = \"A\"\n", "t.toml").def.obstruction;
  EXPECT_EQ(a.shape, gapflow::ObstructionShape::triangle);
  EXPECT_EQ(a.apex, gapflow::Apex::away_from_gap);
  EXPECT_EQ(a.preset, "A");
  auto v = gapflow::parse_scenario(kHead + "[obstruction]\nshape = \"V\"\n", "t.toml").def.obstruction;
  EXPECT_EQ(v.shape, gapflow::ObstructionShape::triangle);
  EXPECT_EQ(v.apex, gapflow::Apex::toward_gap);
  EXPECT_EQ(v.preset, "V");
  // An apex that agrees with the preset is fine.
  auto a2 = gapflow::parse_scenario(kHead + "[obstruction]\nshape = \"A\"\napex = \"away_from_gap\"\n", "t.toml");
  EXPECT_EQ(a2.def.obstruction.apex, gapflow::Apex::away_from_gap);
  auto t = gapflow::parse_scenario(kHead + "[obstruction]\nshape = \"triangle\"\napex = \"toward_gap\"\n", "t.toml");
  EXPECT_EQ(t.def.obstruction.apex, gapflow::Apex::toward_gap);
  EXPECT_EQ(t.def.obstruction.preset, "");
}

TEST(ScenarioLoader, ClockwisePolygonIsReversed) {
  auto s = gapflow::parse_scenario(
      kHead + "[obstruction]\nshape = \"polygon\"\nvertices_mm = [[0, 0], [0, 10], [10, 0]]\n", "t.toml");
  const auto& v = s.def.obstruction.vertices_mm;
  ASSERT_EQ(v.size(), 3u);
  EXPECT_DOUBLE_EQ(v[0].x, 10);
  EXPECT_DOUBLE_EQ(v[0].y, 0);
  EXPECT_DOUBLE_EQ(v[1].x, 0);
  EXPECT_DOUBLE_EQ(v[1].y, 10);
  EXPECT_DOUBLE_EQ(v[2].x, 0);
  EXPECT_DOUBLE_EQ(v[2].y, 0);
  double area2 = 0;
  for (std::size_t i = 0; i < v.size(); ++i) {
    const auto& a = v[i];
    const auto& b = v[(i + 1) % v.size()];
    area2 += a.x * b.y - b.x * a.y;
  }
  EXPECT_GT(area2, 0);
}

TEST(ScenarioLoader, CounterClockwisePolygonIsKept) {
  auto s = gapflow::parse_scenario(
      kHead + "[obstruction]\nshape = \"polygon\"\nvertices_mm = [[-5, 0], [5, 0], [5, 8], [-5, 8]]\n", "t.toml");
  const auto& v = s.def.obstruction.vertices_mm;
  ASSERT_EQ(v.size(), 4u);
  EXPECT_DOUBLE_EQ(v[0].x, -5);
  EXPECT_DOUBLE_EQ(v[3].y, 8);
}

TEST(ScenarioLoader, CenterIsAcceptedAsCentre) {
  auto s = gapflow::parse_scenario(kHead + "[obstruction]\nreference = \"center\"\n", "t.toml");
  EXPECT_EQ(s.def.obstruction.reference, gapflow::DistanceReference::centre);
}

TEST(ScenarioLoader, KeysOfAnotherShapeAreIgnored) {
  const std::string cylinder = kHead + "[obstruction]\nshape = \"cylinder\"\ndiameter_mm = 30\ndistance_mm = 40\n";
  auto s = gapflow::parse_scenario(cylinder, "t.toml", {"obstruction.shape=A"});
  EXPECT_EQ(s.def.obstruction.shape, gapflow::ObstructionShape::triangle);
  EXPECT_EQ(s.def.obstruction.preset, "A");
  EXPECT_DOUBLE_EQ(s.def.obstruction.diameter_mm, ScenarioDef{}.obstruction.diameter_mm);
  EXPECT_DOUBLE_EQ(s.def.obstruction.distance_mm, 40);
  // A polygon's vertices do not matter to a cylinder, even if they are not a polygon.
  auto c = gapflow::parse_scenario(kHead + "[obstruction]\nshape = \"cylinder\"\nvertices_mm = [[0, 0]]\n", "t.toml");
  EXPECT_EQ(c.def.obstruction.shape, gapflow::ObstructionShape::cylinder);
  EXPECT_TRUE(c.def.obstruction.vertices_mm.empty());
}

TEST(ScenarioLoader, NPassedWithinCount) {
  auto s = gapflow::parse_scenario(kHead + "[particles]\ncount = 10\n[run]\nend = \"n_passed\"\nn_passed = 10\n",
                                   "t.toml");
  EXPECT_EQ(s.def.run.end, gapflow::EndCondition::n_passed);
  EXPECT_EQ(s.def.run.n_passed, 10);
  // stop_after_no_flow_s = 0 means never, whatever the clog timeout.
  auto never = gapflow::parse_scenario(kHead + "[run]\nclog_timeout_s = 5\nstop_after_no_flow_s = 0\n", "t.toml");
  EXPECT_DOUBLE_EQ(never.def.run.stop_after_no_flow_s, 0);
}

// ------------------------------------------------------------------ overrides

TEST(ScenarioLoader, OverridesReplaceFileValuesAndAreLocated) {
  const std::string text = kHead + "[obstruction]\nshape = \"triangle\"\ndistance_mm = 40\n";
  auto s = gapflow::parse_scenario(text, "t.toml",
                                   {"particles.diameter_mm=small", "obstruction.distance_mm=12.5",
                                    "obstruction.shape=cylinder", "scenario.name=renamed run"});
  EXPECT_DOUBLE_EQ(s.def.particles.diameter_mm, 6.15);
  EXPECT_DOUBLE_EQ(s.def.obstruction.distance_mm, 12.5);
  EXPECT_EQ(s.def.obstruction.shape, gapflow::ObstructionShape::cylinder);
  EXPECT_EQ(s.def.name, "renamed run");
  const auto& at = s.where.at("obstruction.distance_mm");
  EXPECT_EQ(at.source, "--set");
  EXPECT_EQ(at.line, 2);
  EXPECT_EQ(at.column, 25);  // "obstruction.distance_mm=" is 24 characters
  EXPECT_EQ(s.where.at("obstruction.shape").line, 3);
  EXPECT_EQ(s.where.at("particles.diameter_mm").source, "--set");
}

TEST(ScenarioLoader, OverrideErrorNamesTheOverride) {
  auto e = error_of(kHead, {"bottleneck.gap_mm=-3"});
  ASSERT_TRUE(e);
  EXPECT_EQ(std::string(e->what()), "--set:1:19: key 'bottleneck.gap_mm' = -3: must be in (0, 100000] (mm)");
}

TEST(ScenarioLoader, OverrideCanAddSectionsAndArrays) {
  auto s = gapflow::parse_scenario(kHead, "t.toml",
                                   {"obstruction.shape=polygon", "obstruction.vertices_mm=[[0,0],[10,0],[0,10]]",
                                    "shaking.walls.enabled=true", "run.seed=7"});
  EXPECT_EQ(s.def.obstruction.vertices_mm.size(), 3u);
  EXPECT_TRUE(s.def.shaking.walls.enabled);
  EXPECT_EQ(s.def.run.seed, 7u);
}

// ------------------------------------------------------------------ canonical text and hash

void expect_same(const gapflow::ShakeDef& a, const gapflow::ShakeDef& b) {
  EXPECT_EQ(a.enabled, b.enabled);
  EXPECT_EQ(a.amplitude_mm, b.amplitude_mm);
  EXPECT_EQ(a.direction_deg, b.direction_deg);
  EXPECT_EQ(a.mirror, b.mirror);
  EXPECT_EQ(a.decay_s, b.decay_s);
  EXPECT_EQ(a.period_s, b.period_s);
  EXPECT_EQ(a.start_s, b.start_s);
  EXPECT_EQ(a.frequency_hz, b.frequency_hz);
}

void expect_same_particles(const gapflow::ParticlesDef& a, const gapflow::ParticlesDef& b) {
  EXPECT_EQ(a.count, b.count);
  EXPECT_EQ(a.diameter_mm, b.diameter_mm);
  EXPECT_EQ(a.size_scatter, b.size_scatter);
  EXPECT_EQ(a.size_distribution, b.size_distribution);
  EXPECT_EQ(a.density_kg_m3, b.density_kg_m3);
  EXPECT_EQ(a.friction_particle, b.friction_particle);
  EXPECT_EQ(a.friction_wall, b.friction_wall);
  EXPECT_EQ(a.friction_base, b.friction_base);
  EXPECT_EQ(a.restitution, b.restitution);
  EXPECT_EQ(a.rolling_resistance, b.rolling_resistance);
  EXPECT_EQ(a.spinning_friction_mm, b.spinning_friction_mm);
}

void expect_same_obstruction(const gapflow::ObstructionDef& a, const gapflow::ObstructionDef& b) {
  EXPECT_EQ(a.shape, b.shape);
  EXPECT_EQ(a.preset, b.preset);
  EXPECT_EQ(a.diameter_mm, b.diameter_mm);
  EXPECT_EQ(a.side_mm, b.side_mm);
  EXPECT_EQ(a.apex, b.apex);
  ASSERT_EQ(a.vertices_mm.size(), b.vertices_mm.size());
  for (std::size_t i = 0; i < a.vertices_mm.size(); ++i) {
    EXPECT_EQ(a.vertices_mm[i].x, b.vertices_mm[i].x);
    EXPECT_EQ(a.vertices_mm[i].y, b.vertices_mm[i].y);
  }
  EXPECT_EQ(a.distance_mm, b.distance_mm);
  EXPECT_EQ(a.reference, b.reference);
  EXPECT_EQ(a.lateral_offset_mm, b.lateral_offset_mm);
}

void expect_same_model(const gapflow::ModelDef& a, const gapflow::ModelDef& b) {
  EXPECT_EQ(a.box2d.time_step_s, b.box2d.time_step_s);
  EXPECT_EQ(a.box2d.velocity_iterations, b.box2d.velocity_iterations);
  EXPECT_EQ(a.box2d.position_iterations, b.box2d.position_iterations);
  EXPECT_EQ(a.box2d.sleeping, b.box2d.sleeping);
  EXPECT_EQ(a.box2d.continuous_collision, b.box2d.continuous_collision);
  EXPECT_EQ(a.box2d.engine_diameter, b.box2d.engine_diameter);
  EXPECT_EQ(a.box2d.rolling.enabled, b.box2d.rolling.enabled);
  EXPECT_EQ(a.box2d.rolling.inertia_factor, b.box2d.rolling.inertia_factor);
  EXPECT_EQ(a.box2d.base_friction.enabled, b.box2d.base_friction.enabled);
  EXPECT_EQ(a.box2d.base_friction.method, b.box2d.base_friction.method);
  EXPECT_EQ(a.bullet.time_step_s, b.bullet.time_step_s);
  EXPECT_EQ(a.bullet.substeps, b.bullet.substeps);
  EXPECT_EQ(a.bullet.solver_iterations, b.bullet.solver_iterations);
  EXPECT_EQ(a.bullet.sleeping, b.bullet.sleeping);
  EXPECT_EQ(a.bullet.engine_diameter, b.bullet.engine_diameter);
  EXPECT_EQ(a.bullet.wall_height_d, b.bullet.wall_height_d);
  EXPECT_EQ(a.bullet.collision_margin_d, b.bullet.collision_margin_d);
}

// Field by field: a field missing from canonical_toml would still give equal texts.
void expect_same(const ScenarioDef& a, const ScenarioDef& b) {
  EXPECT_EQ(a.name, b.name);
  EXPECT_EQ(a.description, b.description);
  EXPECT_EQ(a.plane.incline_deg, b.plane.incline_deg);
  EXPECT_EQ(a.plane.length_mm, b.plane.length_mm);
  EXPECT_EQ(a.plane.width_mm, b.plane.width_mm);
  EXPECT_EQ(a.bottleneck.wall_angle_deg, b.bottleneck.wall_angle_deg);
  EXPECT_EQ(a.bottleneck.gap_mm, b.bottleneck.gap_mm);
  EXPECT_EQ(a.bottleneck.wall_thickness_mm, b.bottleneck.wall_thickness_mm);
  expect_same_particles(a.particles, b.particles);
  EXPECT_EQ(a.release.barrier_mm, b.release.barrier_mm);
  EXPECT_EQ(a.release.settle_s, b.release.settle_s);
  EXPECT_EQ(a.release.lattice_gap, b.release.lattice_gap);
  expect_same_obstruction(a.obstruction, b.obstruction);
  expect_same(a.shaking.walls, b.shaking.walls);
  expect_same(a.shaking.obstruction, b.shaking.obstruction);
  EXPECT_EQ(a.protocol.clog_breaking, b.protocol.clog_breaking);
  EXPECT_EQ(a.protocol.reinject_passed, b.protocol.reinject_passed);
  EXPECT_EQ(a.protocol.perturb_radius_d, b.protocol.perturb_radius_d);
  EXPECT_EQ(a.run.end, b.run.end);
  EXPECT_EQ(a.run.time_limit_s, b.run.time_limit_s);
  EXPECT_EQ(a.run.n_passed, b.run.n_passed);
  EXPECT_EQ(a.run.clog_timeout_s, b.run.clog_timeout_s);
  EXPECT_EQ(a.run.stop_after_no_flow_s, b.run.stop_after_no_flow_s);
  EXPECT_EQ(a.run.stranded_max, b.run.stranded_max);
  EXPECT_EQ(a.run.seed, b.run.seed);
  EXPECT_EQ(a.run.replicate, b.run.replicate);
  expect_same_model(a.model, b.model);
}

// A valid scenario in which every field differs from its default.
ScenarioDef all_fields_changed() {
  ScenarioDef d;
  d.name = "round \"trip\"\t\\ é";
  d.description = "line one\nline two";
  d.plane = {12.5, 1234.5, 321.0};
  d.bottleneck = {45.0, 1.0 / 3.0 * 100, 12.0};
  d.particles = {500, 6.15, 0.1, gapflow::SizeDistribution::normal, 2400.5, 0.3, 0.25, 0.2, 0.5, 0.01, 0.125};
  d.release = {20.0, 1.25, 0.1};
  d.obstruction.shape = gapflow::ObstructionShape::polygon;
  d.obstruction.diameter_mm = 50.0;  // ignored for a polygon: stays at its default
  d.obstruction.vertices_mm = {{-10, 0}, {10.1, 0}, {0.3, 17.32}};
  d.obstruction.distance_mm = 25.4;
  d.obstruction.reference = gapflow::DistanceReference::centre;
  d.obstruction.lateral_offset_mm = -1e-7;
  d.shaking.walls = {true, 0.75, 90.0, false, 0.5, 2.0, 1.5, 30.0};
  d.shaking.obstruction = {true, 1.0, -45.0, false, 0.25, 0.5, 0.1, 7.5};
  d.run = {gapflow::EndCondition::time_limit, 120.0, 400, 2.5, 10.0, 7, 1234567890123ull, 3};
  d.protocol = {gapflow::ClogBreaking::local_perturbation, true, 4.5};
  d.model.box2d = {0.0004, 12, 4, true, true, 2.5, 0.0, 0.5, {false, 2.0 / 3.0}, {false, gapflow::BaseFrictionMethod::joint}};
  d.model.bullet = {0.0005, 4, 50, true, 10.0, 3.5, 0.05};
  // (model.box2d.rolling_contact needs rolling on: its round trip is in tests/test_rolling_contact.cpp)
  return d;
}

TEST(ScenarioCanonical, EveryFieldRoundTrips) {
  const ScenarioDef d = all_fields_changed();
  const std::string text = gapflow::canonical_toml(d);
  LoadedScenario back = gapflow::parse_scenario(text, "canonical.toml");
  expect_same(back.def, d);
  EXPECT_EQ(gapflow::canonical_toml(back.def), text);
  EXPECT_EQ(gapflow::scenario_hash(back.def), gapflow::scenario_hash(d));
}

TEST(ScenarioCanonical, DefaultsAndPresetsRoundTrip) {
  for (const char* shape : {"none", "cylinder", "A", "V", "triangle"}) {
    SCOPED_TRACE(shape);
    auto s = gapflow::parse_scenario(kHead + "[obstruction]\nshape = \"" + shape + "\"\n", "t.toml");
    const std::string text = gapflow::canonical_toml(s.def);
    auto back = gapflow::parse_scenario(text, "canonical.toml");
    expect_same(back.def, s.def);
    EXPECT_EQ(gapflow::canonical_toml(back.def), text);
    EXPECT_EQ(gapflow::scenario_hash(back.def), gapflow::scenario_hash(s.def));
  }
}

TEST(ScenarioCanonical, FloatsAreShortestRoundTrip) {
  ScenarioDef d;
  d.name = "f";
  d.bottleneck.gap_mm = 0.1 + 0.2;  // 0.30000000000000004
  d.plane.length_mm = 1000;
  const std::string text = gapflow::canonical_toml(d);
  EXPECT_NE(text.find("gap_mm = 0.30000000000000004\n"), std::string::npos) << text;
  EXPECT_NE(text.find("length_mm = 1000.0\n"), std::string::npos) << text;
  EXPECT_NE(text.find("[model.box2d.base_friction]\n"), std::string::npos) << text;
}

TEST(ScenarioHash, ChangesWithAnyValueAndOnlyWithValues) {
  const std::string text = kHead + "[bottleneck]\ngap_mm = 33\n";
  auto a = gapflow::parse_scenario(text, "a.toml").def;
  auto same = gapflow::parse_scenario(kHead + "# a comment\n[bottleneck]\ngap_mm = 33.0\n", "b.toml").def;
  EXPECT_EQ(gapflow::scenario_hash(a), gapflow::scenario_hash(same));
  auto seed = gapflow::parse_scenario(text, "a.toml", {"run.seed=2"}).def;
  EXPECT_NE(gapflow::scenario_hash(a), gapflow::scenario_hash(seed));
  auto gap = gapflow::parse_scenario(text, "a.toml", {"bottleneck.gap_mm=33.000000001"}).def;
  EXPECT_NE(gapflow::scenario_hash(a), gapflow::scenario_hash(gap));
  auto mirror = gapflow::parse_scenario(text, "a.toml", {"shaking.obstruction.mirror=false"}).def;
  EXPECT_NE(gapflow::scenario_hash(a), gapflow::scenario_hash(mirror));
}

// ------------------------------------------------------------------ files

struct TempFile {
  std::filesystem::path path;
  explicit TempFile(const std::string& text)
      : path(std::filesystem::temp_directory_path() /
             ("gapflow_loader_" + std::to_string(::testing::UnitTest::GetInstance()->random_seed()) + "_" +
              ::testing::UnitTest::GetInstance()->current_test_info()->name() + ".toml")) {
    std::ofstream(path) << text;
  }
  ~TempFile() { std::filesystem::remove(path); }
};

TEST(ScenarioLoader, LoadsFileAndNamesItInErrors) {
  TempFile good(kHead + "[plane]\nwidth_mm = 250\n");
  auto s = gapflow::load_scenario(good.path, {"plane.length_mm=900"});
  EXPECT_EQ(s.source, good.path.string());
  EXPECT_DOUBLE_EQ(s.def.plane.width_mm, 250);
  EXPECT_DOUBLE_EQ(s.def.plane.length_mm, 900);
  EXPECT_EQ(s.where.at("plane.width_mm").source, good.path.string());

  TempFile bad(kHead + "[plane]\nwidth_mm = -1\n");
  try {
    gapflow::load_scenario(bad.path);
    FAIL() << "accepted";
  } catch (const ScenarioError& e) {
    EXPECT_EQ(std::string(e.what()).rfind(bad.path.string() + ":4:", 0), 0u) << e.what();
  }
  EXPECT_THROW(gapflow::load_scenario(bad.path.string() + ".missing"), ScenarioError);
}

TEST(ScenarioFiles, EveryShippedScenarioLoadsCompilesAndRoundTrips) {
  const auto dir = gapflow::testing::source_path("scenarios");
  std::vector<std::filesystem::path> files;
  if (std::filesystem::is_directory(dir))
    for (const auto& entry : std::filesystem::recursive_directory_iterator(dir))
      if (entry.is_regular_file() && entry.path().extension() == ".toml") files.push_back(entry.path());
  if (files.empty()) GTEST_SKIP() << "no scenario files under " << dir;
  for (const auto& file : files) {
    SCOPED_TRACE(file.string());
    try {
      LoadedScenario s = gapflow::load_scenario(file);
      const std::string text = gapflow::canonical_toml(s.def);
      auto back = gapflow::parse_scenario(text, "canonical.toml");
      expect_same(back.def, s.def);
      EXPECT_EQ(gapflow::canonical_toml(back.def), text);
      try {
        gapflow::compile_scenario(s.def);
      } catch (const ScenarioInvalid& e) {
        ADD_FAILURE() << gapflow::locate(e, s).what();
      }
    } catch (const ScenarioError& e) {
      ADD_FAILURE() << e.what();
    }
  }
}

// ------------------------------------------------------------------ cross-field errors, located

std::optional<ScenarioError> compile_error(const std::string& text, const std::vector<std::string>& overrides = {}) {
  try {
    gapflow::testing::compile_text(text, overrides);
  } catch (const ScenarioError& e) {
    return e;
  }
  return std::nullopt;
}

TEST(ScenarioCompile, GapWiderThanChannelIsLocatedAtTheGap) {
  auto e = compile_error(kHead + "[plane]\nwidth_mm = 300\n[bottleneck]\nwall_angle_deg = 30\ngap_mm = 350\n");
  ASSERT_TRUE(e);
  EXPECT_EQ(e->key(), "bottleneck.gap_mm") << e->what();
  EXPECT_EQ(e->where().line, 7) << e->what();
  EXPECT_EQ(e->where().source, "test.toml");
}

TEST(ScenarioCompile, GapSetByOverrideIsLocatedAtTheOverride) {
  auto e = compile_error(kHead + "[plane]\nwidth_mm = 300\n", {"run.seed=3", "bottleneck.gap_mm=400"});
  ASSERT_TRUE(e);
  EXPECT_EQ(e->key(), "bottleneck.gap_mm") << e->what();
  EXPECT_EQ(e->where().source, "--set") << e->what();
  EXPECT_EQ(e->where().line, 2) << e->what();
}

TEST(ScenarioCompile, DefaultGapTooWideIsLocatedAtItsSection) {
  // The gap keeps its default (33 mm); the channel is made narrower than it.
  auto e = compile_error(kHead + "[bottleneck]\nwall_angle_deg = 30\n[plane]\nwidth_mm = 20\n[particles]\ncount = 5\n");
  ASSERT_TRUE(e);
  EXPECT_EQ(e->key(), "bottleneck.gap_mm") << e->what();
  EXPECT_EQ(e->where().line, 3) << e->what();
  EXPECT_NE(e->value().find("(default)"), std::string::npos) << e->what();
}

TEST(ScenarioCompile, ObstructionOverlappingAWallIsLocatedAtItsDistance) {
  auto e = compile_error(kHead +
                         "[obstruction]\nshape = \"cylinder\"\ndiameter_mm = 100\n"
                         "# touching the gap line: wider than the funnel there\ndistance_mm = 0\n");
  ASSERT_TRUE(e);
  EXPECT_EQ(e->key(), "obstruction.distance_mm") << e->what();
  EXPECT_EQ(e->where().line, 7) << e->what();
}

// ------------------------------------------------------------------ locate()

TEST(ScenarioLocate, FallsBackFromKeyToSectionToFileStart) {
  auto s = gapflow::parse_scenario(kHead + "\n[bottleneck]\nwall_angle_deg = 40\ngap_mm = 20\n", "loc.toml");
  auto at_key = gapflow::locate(ScenarioInvalid("bottleneck.gap_mm", "20", "too narrow"), s);
  EXPECT_EQ(at_key.where().line, 6);
  EXPECT_EQ(at_key.value(), "20");
  EXPECT_EQ(std::string(at_key.what()).rfind("loc.toml:6:", 0), 0u) << at_key.what();

  auto at_section = gapflow::locate(ScenarioInvalid("bottleneck.wall_thickness_mm", "10", "too thin"), s);
  EXPECT_EQ(at_section.where().line, 4);
  EXPECT_EQ(at_section.value(), "10 (default)");

  auto at_start = gapflow::locate(ScenarioInvalid("plane.length_mm", "1000", "too short"), s);
  EXPECT_EQ(at_start.where().source, "loc.toml");
  EXPECT_EQ(at_start.where().line, 1);
  EXPECT_EQ(at_start.where().column, 1);
  EXPECT_EQ(at_start.value(), "1000 (default)");
  EXPECT_EQ(std::string(at_start.what()), "loc.toml:1:1: key 'plane.length_mm' = 1000 (default): too short");
}

TEST(ScenarioEnums, StringsAreTheTomlValues) {
  EXPECT_STREQ(gapflow::to_string(gapflow::SizeDistribution::uniform), "uniform");
  EXPECT_STREQ(gapflow::to_string(gapflow::ObstructionShape::polygon), "polygon");
  EXPECT_STREQ(gapflow::to_string(gapflow::DistanceReference::centre), "centre");
  EXPECT_STREQ(gapflow::to_string(gapflow::Apex::toward_gap), "toward_gap");
  EXPECT_STREQ(gapflow::to_string(gapflow::EndCondition::n_passed), "n_passed");
  EXPECT_STREQ(gapflow::to_string(gapflow::BaseFrictionMethod::joint), "joint");
}

}  // namespace
